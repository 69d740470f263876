// SPDX-License-Identifier: MIT
// The communicator over MPI (UVR_ENABLE_MPI=ON). Every MPI call's return code is checked (the
// communicator's error handler is MPI_ERRORS_RETURN) and a failure becomes an Io error naming the
// call. Messages move in pieces of at most maxChunkBytes, as MPI's counts are int.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <deque>
#include <string>
#include <thread>

#include "uvr/core/error.h"
#include "uvr/dist/mpi_communicator.h"

namespace uvr {

namespace {

/// The tags of the point-to-point traffic, one per use, so none matches another's message.
enum Tag { kTagSend = 1, kTagExchange = 2, kTagGather = 3, kTagAllToAll = 4 };

/// Throws an Io error naming the MPI call and MPI's words for the code, unless rc is success.
void check(int rc, const char* call) {
    if (rc == MPI_SUCCESS) return;
    char text[MPI_MAX_ERROR_STRING] = {};
    int length = 0;
    std::string reason = MPI_Error_string(rc, text, &length) == MPI_SUCCESS
                             ? std::string(text, std::size_t(std::max(length, 0)))
                             : "error code " + std::to_string(rc);
    throwError(ErrorKind::Io, "", std::string(call) + " failed: " + reason);
}

/// MPI's operation for a ReduceOp.
MPI_Op mpiOp(ReduceOp op) {
    switch (op) {
        case ReduceOp::Sum:
            return MPI_SUM;
        case ReduceOp::Min:
            return MPI_MIN;
        case ReduceOp::Max:
            return MPI_MAX;
    }
    return MPI_SUM;
}

/// The communicator over a duplicate of a parent communicator.
class MpiCommunicator final : public Communicator {
public:
    MpiCommunicator(MPI_Comm parent, std::size_t maxChunkBytes) : chunk_(maxChunkBytes) {
        if (maxChunkBytes < 1 || maxChunkBytes > std::size_t(INT_MAX))
            throwError(ErrorKind::Argument, "",
                       "an MPI message piece of " + std::to_string(maxChunkBytes) +
                           " bytes: expected 1 to " + std::to_string(INT_MAX));
        check(MPI_Comm_dup(parent, &comm_), "MPI_Comm_dup");
        check(MPI_Comm_set_errhandler(comm_, MPI_ERRORS_RETURN), "MPI_Comm_set_errhandler");
        check(MPI_Comm_rank(comm_, &rank_), "MPI_Comm_rank");
        check(MPI_Comm_size(comm_, &size_), "MPI_Comm_size");
    }

    ~MpiCommunicator() override {
        int finalized = 1;
        if (MPI_Finalized(&finalized) == MPI_SUCCESS && !finalized) MPI_Comm_free(&comm_);
    }

    MpiCommunicator(const MpiCommunicator&) = delete;
    MpiCommunicator& operator=(const MpiCommunicator&) = delete;

    int rank() const override { return rank_; }
    int size() const override { return size_; }

    void barrier() override { check(MPI_Barrier(comm_), "MPI_Barrier"); }

    void broadcast(std::vector<std::byte>& bytes, int root) override {
        detail::checkRankArgument(*this, root, "broadcast", "root");
        std::uint64_t count = bytes.size();
        check(MPI_Bcast(&count, 1, MPI_UINT64_T, root, comm_), "MPI_Bcast");
        if (rank_ != root) bytes.resize(count);
        broadcastPieces(bytes.data(), bytes.size(), root);
    }

    std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) override {
        std::vector<std::uint64_t> counts = allGatherCounts(mine.size());
        std::vector<std::vector<std::byte>> all(size_);
        std::uint64_t total = 0;
        for (std::uint64_t count : counts) total += count;
        if (total <= chunk_) {
            // One MPI_Allgatherv into one buffer, then cut into the ranks' parts.
            std::vector<int> sizes(size_), offsets(size_);
            for (int r = 0, offset = 0; r < size_; ++r) {
                sizes[r] = int(counts[r]);
                offsets[r] = offset;
                offset += sizes[r];
            }
            std::vector<std::byte> flat(total);
            check(MPI_Allgatherv(mine.data(), int(mine.size()), MPI_BYTE, flat.data(), sizes.data(),
                                 offsets.data(), MPI_BYTE, comm_),
                  "MPI_Allgatherv");
            for (int r = 0; r < size_; ++r)
                all[r].assign(flat.begin() + offsets[r], flat.begin() + offsets[r] + sizes[r]);
        } else {
            // Larger than one piece: each rank's part broadcast in pieces from it.
            for (int r = 0; r < size_; ++r) {
                if (r == rank_)
                    all[r].assign(mine.begin(), mine.end());
                else
                    all[r].resize(counts[r]);
                broadcastPieces(all[r].data(), all[r].size(), r);
            }
        }
        return all;
    }

    std::vector<std::vector<std::byte>> gather(std::span<const std::byte> mine, int root) override {
        std::vector<std::vector<std::byte>> all;
        gatherInto(mine, root, all);
        return all;
    }

    void gatherInto(std::span<const std::byte> mine, int root,
                    std::vector<std::vector<std::byte>>& all) override {
        detail::checkRankArgument(*this, root, "gather", "root");
        std::uint64_t count = mine.size();
        std::vector<std::uint64_t> counts(rank_ == root ? size_ : 0);
        check(MPI_Gather(&count, 1, MPI_UINT64_T, counts.data(), 1, MPI_UINT64_T, root, comm_),
              "MPI_Gather");
        std::vector<MPI_Request> requests;
        if (rank_ == root) {
            all.resize(size_);
            for (int r = 0; r < size_; ++r) {
                if (r == rank_) {
                    all[r].assign(mine.begin(), mine.end());
                } else {
                    all[r].resize(counts[r]);
                    postReceives(all[r].data(), all[r].size(), r, kTagGather, requests);
                }
            }
        } else {
            all.clear();
            postSends(mine.data(), mine.size(), root, kTagGather, requests);
        }
        waitAll(requests);
    }

    std::vector<std::vector<std::byte>> allToAll(
        const std::vector<std::vector<std::byte>>& toEach) override {
        std::vector<std::vector<std::byte>> fromEach;
        allToAllInto(toEach, fromEach);
        return fromEach;
    }

    void allToAllInto(const std::vector<std::vector<std::byte>>& toEach,
                      std::vector<std::vector<std::byte>>& fromEach) override {
        if (int(toEach.size()) != size_)
            throwError(ErrorKind::Argument, "",
                       "allToAll: " + std::to_string(toEach.size()) + " messages for " +
                           std::to_string(size_) + " ranks");
        std::vector<std::uint64_t> sendCounts(size_), receiveCounts(size_);
        for (int r = 0; r < size_; ++r) sendCounts[r] = toEach[r].size();
        check(MPI_Alltoall(sendCounts.data(), 1, MPI_UINT64_T, receiveCounts.data(), 1,
                           MPI_UINT64_T, comm_),
              "MPI_Alltoall");
        fromEach.resize(size_);
        std::vector<MPI_Request> requests;
        for (int r = 0; r < size_; ++r) {
            if (r == rank_) continue;
            fromEach[r].resize(receiveCounts[r]);
            postReceives(fromEach[r].data(), fromEach[r].size(), r, kTagAllToAll, requests);
        }
        for (int r = 0; r < size_; ++r)
            if (r != rank_)
                postSends(toEach[r].data(), toEach[r].size(), r, kTagAllToAll, requests);
        fromEach[rank_].assign(toEach[rank_].begin(), toEach[rank_].end());
        waitAll(requests);
    }

    std::vector<std::byte> exchange(int peer, std::span<const std::byte> send) override {
        detail::checkRankArgument(*this, peer, "exchange", "peer");
        std::uint64_t sendCount = send.size(), receiveCount = 0;
        check(MPI_Sendrecv(&sendCount, 1, MPI_UINT64_T, peer, kTagExchange, &receiveCount, 1,
                           MPI_UINT64_T, peer, kTagExchange, comm_, MPI_STATUS_IGNORE),
              "MPI_Sendrecv");
        std::vector<std::byte> received(receiveCount);
        std::vector<MPI_Request> requests;
        postReceives(received.data(), received.size(), peer, kTagExchange, requests);
        postSends(send.data(), send.size(), peer, kTagExchange, requests);
        waitAll(requests);
        return received;
    }

    void send(int to, std::span<const std::byte> bytes) override {
        detail::checkRankArgument(*this, to, "send", "destination");
        if (to == rank_) {
            // A blocking MPI_Send to itself would wait for its own receive: queued here.
            toMyself_.emplace_back(bytes.begin(), bytes.end());
            return;
        }
        std::uint64_t count = bytes.size();
        check(MPI_Send(&count, 1, MPI_UINT64_T, to, kTagSend, comm_), "MPI_Send");
        for (std::size_t offset = 0; offset < bytes.size(); offset += chunk_) {
            int piece = int(std::min(chunk_, bytes.size() - offset));
            check(MPI_Send(bytes.data() + offset, piece, MPI_BYTE, to, kTagSend, comm_),
                  "MPI_Send");
        }
    }

    std::vector<std::byte> receive(int from) override {
        detail::checkRankArgument(*this, from, "receive", "source");
        if (from == rank_) {
            if (toMyself_.empty())
                throwError(ErrorKind::Internal, "",
                           "rank " + std::to_string(rank_) +
                               " receives from itself with nothing sent: it would wait forever");
            std::vector<std::byte> message = std::move(toMyself_.front());
            toMyself_.pop_front();
            return message;
        }
        std::uint64_t count = 0;
        check(MPI_Recv(&count, 1, MPI_UINT64_T, from, kTagSend, comm_, MPI_STATUS_IGNORE),
              "MPI_Recv");
        std::vector<std::byte> bytes(count);
        for (std::size_t offset = 0; offset < bytes.size(); offset += chunk_) {
            int piece = int(std::min(chunk_, bytes.size() - offset));
            check(MPI_Recv(bytes.data() + offset, piece, MPI_BYTE, from, kTagSend, comm_,
                           MPI_STATUS_IGNORE),
                  "MPI_Recv");
        }
        return bytes;
    }

    std::vector<std::byte> receiveIdle(int from) override {
        detail::checkRankArgument(*this, from, "receive", "source");
        // Open MPI's blocking receive polls without pause: a viewer's ranks wait for the
        // next frame for minutes.
        for (int arrived = 0; from != rank_;) {
            check(MPI_Iprobe(from, kTagSend, comm_, &arrived, MPI_STATUS_IGNORE), "MPI_Iprobe");
            if (arrived) break;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        return receive(from);
    }

    void allReduce(std::span<double> values, ReduceOp op) override {
        reduceAll(values.data(), values.size(), MPI_DOUBLE, op);
    }
    void allReduce(std::span<std::uint64_t> values, ReduceOp op) override {
        reduceAll(values.data(), values.size(), MPI_UINT64_T, op);
    }

private:
    /// Every rank's count, indexed by rank.
    std::vector<std::uint64_t> allGatherCounts(std::uint64_t mine) {
        std::vector<std::uint64_t> counts(size_);
        check(MPI_Allgather(&mine, 1, MPI_UINT64_T, counts.data(), 1, MPI_UINT64_T, comm_),
              "MPI_Allgather");
        return counts;
    }

    /// Broadcasts `count` bytes (known on every rank) from root, a piece at a time.
    void broadcastPieces(std::byte* data, std::size_t count, int root) {
        for (std::size_t offset = 0; offset < count; offset += chunk_) {
            int piece = int(std::min(chunk_, count - offset));
            check(MPI_Bcast(data + offset, piece, MPI_BYTE, root, comm_), "MPI_Bcast");
        }
    }

    /// Starts receiving `count` bytes from a rank, a piece per request.
    void postReceives(std::byte* data, std::size_t count, int from, int tag,
                      std::vector<MPI_Request>& requests) {
        for (std::size_t offset = 0; offset < count; offset += chunk_) {
            int piece = int(std::min(chunk_, count - offset));
            check(MPI_Irecv(data + offset, piece, MPI_BYTE, from, tag, comm_,
                            &requests.emplace_back()),
                  "MPI_Irecv");
        }
    }

    /// Starts sending `count` bytes to a rank, a piece per request.
    void postSends(const std::byte* data, std::size_t count, int to, int tag,
                   std::vector<MPI_Request>& requests) {
        for (std::size_t offset = 0; offset < count; offset += chunk_) {
            int piece = int(std::min(chunk_, count - offset));
            check(
                MPI_Isend(data + offset, piece, MPI_BYTE, to, tag, comm_, &requests.emplace_back()),
                "MPI_Isend");
        }
    }

    /// Waits for every request started.
    void waitAll(std::vector<MPI_Request>& requests) {
        if (requests.empty()) return;
        check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE),
              "MPI_Waitall");
        requests.clear();
    }

    /// Reduces in place, a piece of at most chunk_ bytes at a time.
    template <class T>
    void reduceAll(T* values, std::size_t count, MPI_Datatype type, ReduceOp op) {
        const std::size_t piece = std::max<std::size_t>(1, chunk_ / sizeof(T));
        for (std::size_t offset = 0; offset < count; offset += piece) {
            int n = int(std::min(piece, count - offset));
            check(MPI_Allreduce(MPI_IN_PLACE, values + offset, n, type, mpiOp(op), comm_),
                  "MPI_Allreduce");
        }
    }

    MPI_Comm comm_ = MPI_COMM_NULL;
    int rank_ = 0, size_ = 1;
    std::size_t chunk_;
    std::deque<std::vector<std::byte>> toMyself_;  ///< messages this rank sent itself, in order
};

/// Finalises MPI at exit (registered only when uvr initialised it).
void finalizeMpi() {
    int finalized = 1;
    if (MPI_Finalized(&finalized) == MPI_SUCCESS && !finalized) MPI_Finalize();
}

/// Initialises MPI unless it is already initialised.
void initializeMpi() {
    int initialized = 0;
    check(MPI_Initialized(&initialized), "MPI_Initialized");
    if (initialized) return;
    int finalized = 0;
    check(MPI_Finalized(&finalized), "MPI_Finalized");
    if (finalized)
        throwError(ErrorKind::Internal, "", "MPI was finalised before uvr's first use of it");
    int provided = MPI_THREAD_SINGLE;
    check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided), "MPI_Init_thread");
    std::atexit(finalizeMpi);
}

}  // namespace

bool builtWithMpi() {
    return true;
}

Communicator& mpiWorld() {
    static MpiCommunicator* world = [] {
        initializeMpi();
        // Never destroyed: MPI_Finalize at exit frees its communicator.
        return new MpiCommunicator(MPI_COMM_WORLD, kMpiMaxChunkBytes);
    }();
    return *world;
}

std::unique_ptr<Communicator> makeMpiCommunicator(std::size_t maxChunkBytes) {
    mpiWorld();
    return std::make_unique<MpiCommunicator>(MPI_COMM_WORLD, maxChunkBytes);
}

}  // namespace uvr

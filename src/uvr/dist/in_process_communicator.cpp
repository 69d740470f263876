// SPDX-License-Identifier: MIT
#include "uvr/dist/in_process_communicator.h"

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "uvr/core/error.h"

namespace uvr {

namespace {

/// The point-to-point channels: send/receive, and exchange (matched separately, as MPI tags).
enum Channel { kUserChannel = 0, kExchangeChannel = 1, kChannels = 2 };

/// The message of any exception.
std::string messageOf(const std::exception_ptr& failure) {
    try {
        std::rethrow_exception(failure);
    } catch (const std::exception& e) {
        return e.what();
    } catch (...) {
        return "an exception that is not a std::exception";
    }
}

/// Applies a reduction to two values.
template <class T>
T reduce(T a, T b, ReduceOp op) {
    switch (op) {
        case ReduceOp::Sum:
            return a + b;
        case ReduceOp::Min:
            return std::min(a, b);
        case ReduceOp::Max:
            return std::max(a, b);
    }
    return a;
}

/// What the ranks of one group share, guarded by one mutex. Collectives use a board: each rank
/// posts a pointer to its contribution, and once all have arrived every rank reads what it
/// needs from the others' contributions; the board is cleared (a new generation) only after
/// every rank has read, so a contribution lives on its owner's stack until then.
class Group {
public:
    explicit Group(int size)
        : size_(size),
          mailboxes_(std::size_t(kChannels) * size * size),
          ended_(size, 0),
          inputs_(size, nullptr) {}

    int size() const { return size_; }

    /// Queues a copy of bytes from `from` to `to` on a channel.
    void post(Channel channel, int from, int to, std::span<const std::byte> bytes) {
        std::vector<std::byte> message(bytes.begin(), bytes.end());
        std::lock_guard lock(mutex_);
        mailbox(channel, from, to).push_back(std::move(message));
        changed_.notify_all();
    }

    /// Waits for the next message from `from` to `to` on a channel; throws (a stop) when it can
    /// never come: the group stopped, or `from` ended.
    std::vector<std::byte> take(Channel channel, int from, int to, bool& stopped) {
        std::unique_lock lock(mutex_);
        std::deque<std::vector<std::byte>>& box = mailbox(channel, from, to);
        if (box.empty() && from == to)
            throwError(ErrorKind::Internal, "",
                       "rank " + std::to_string(to) +
                           " receives from itself with nothing sent: it would wait forever");
        changed_.wait(lock, [&] { return !box.empty() || !stopMessage_.empty() || ended_[from]; });
        if (!box.empty()) {
            std::vector<std::byte> message = std::move(box.front());
            box.pop_front();
            return message;
        }
        stopped = true;
        if (!stopMessage_.empty()) throwError(ErrorKind::Internal, "", stopMessage_);
        throwError(ErrorKind::Internal, "",
                   "rank " + std::to_string(from) + " ended without sending what rank " +
                       std::to_string(to) + " waits to receive");
    }

    /// One collective: posts `input`, waits for every rank's, calls read(inputs) and returns
    /// once every rank has read. Throws (a stop) when a rank can no longer arrive.
    template <class Read>
    void collective(int rank, const void* input, Read&& read, bool& stopped) {
        std::unique_lock lock(mutex_);
        // Arrive: wait for every rank, or for the group to stop short of that.
        inputs_[rank] = input;
        if (++arrived_ == size_) {
            allIn_ = true;
            changed_.notify_all();
        } else {
            changed_.wait(lock, [&] { return allIn_ || !stopMessage_.empty() || endedCount_ > 0; });
        }
        if (!allIn_) {
            --arrived_;
            inputs_[rank] = nullptr;
            stopped = true;
            if (!stopMessage_.empty()) throwError(ErrorKind::Internal, "", stopMessage_);
            int ended = int(std::find(ended_.begin(), ended_.end(), 1) - ended_.begin());
            throwError(ErrorKind::Internal, "",
                       "rank " + std::to_string(ended) + " ended without joining a collective " +
                           "rank " + std::to_string(rank) + " waits in");
        }
        // Read: every rank is here, and no contribution changes until every rank has read.
        lock.unlock();
        std::exception_ptr failure;
        try {
            read(std::span<const void* const>(inputs_));
        } catch (...) {
            failure = std::current_exception();
        }
        // Leave: the last reader clears the board; the others wait for it, as their
        // contributions are still being read until then (reading never waits, so this ends).
        lock.lock();
        std::uint64_t generation = generation_;
        if (++read_ == size_) {
            arrived_ = 0;
            read_ = 0;
            allIn_ = false;
            std::fill(inputs_.begin(), inputs_.end(), nullptr);
            ++generation_;
            changed_.notify_all();
        } else {
            changed_.wait(lock, [&] { return generation_ != generation; });
        }
        lock.unlock();
        if (failure) std::rethrow_exception(failure);
    }

    /// Records that a rank's body has ended (with failure, or null); a failure stops the group.
    void end(int rank, const std::exception_ptr& failure) {
        std::lock_guard lock(mutex_);
        ended_[rank] = 1;
        ++endedCount_;
        if (failure && stopMessage_.empty())
            stopMessage_ = "rank " + std::to_string(rank) + " failed: " + messageOf(failure);
        changed_.notify_all();
    }

private:
    std::deque<std::vector<std::byte>>& mailbox(Channel channel, int from, int to) {
        return mailboxes_[(std::size_t(channel) * size_ + from) * size_ + to];
    }

    const int size_;
    std::mutex mutex_;
    std::condition_variable changed_;
    std::vector<std::deque<std::vector<std::byte>>> mailboxes_;  ///< per (channel, from, to)
    std::string stopMessage_;                                    ///< set by the first failure
    std::vector<char> ended_;                                    ///< per rank: its body ended
    int endedCount_ = 0;
    std::vector<const void*> inputs_;  ///< per rank: its contribution to the collective
    int arrived_ = 0, read_ = 0;
    bool allIn_ = false;
    std::uint64_t generation_ = 0;
};

/// One rank of a Group.
class InProcessCommunicator final : public Communicator {
public:
    InProcessCommunicator(Group& group, int rank) : group_(group), rank_(rank) {}

    /// Whether this rank threw because the group stopped (another rank failed or ended).
    bool stopped() const { return stopped_; }

    int rank() const override { return rank_; }
    int size() const override { return group_.size(); }

    void barrier() override {
        group_.collective(
            rank_, nullptr, [](std::span<const void* const>) {}, stopped_);
    }

    void broadcast(std::vector<std::byte>& bytes, int root) override {
        detail::checkRankArgument(*this, root, "broadcast", "root");
        const bool isRoot = rank_ == root;
        group_.collective(
            rank_, &bytes,
            [&](std::span<const void* const> inputs) {
                if (!isRoot) bytes = *static_cast<const std::vector<std::byte>*>(inputs[root]);
            },
            stopped_);
    }

    std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) override {
        std::vector<std::vector<std::byte>> all(size());
        group_.collective(
            rank_, &mine,
            [&](std::span<const void* const> inputs) {
                for (int r = 0; r < size(); ++r) {
                    auto theirs = static_cast<const std::span<const std::byte>*>(inputs[r]);
                    all[r].assign(theirs->begin(), theirs->end());
                }
            },
            stopped_);
        return all;
    }

    std::vector<std::vector<std::byte>> gather(std::span<const std::byte> mine, int root) override {
        detail::checkRankArgument(*this, root, "gather", "root");
        std::vector<std::vector<std::byte>> all;
        group_.collective(
            rank_, &mine,
            [&](std::span<const void* const> inputs) {
                if (rank_ != root) return;
                all.resize(size());
                for (int r = 0; r < size(); ++r) {
                    auto theirs = static_cast<const std::span<const std::byte>*>(inputs[r]);
                    all[r].assign(theirs->begin(), theirs->end());
                }
            },
            stopped_);
        return all;
    }

    std::vector<std::vector<std::byte>> allToAll(
        const std::vector<std::vector<std::byte>>& toEach) override {
        if (int(toEach.size()) != size())
            throwError(ErrorKind::Argument, "",
                       "allToAll: " + std::to_string(toEach.size()) + " messages for " +
                           std::to_string(size()) + " ranks");
        std::vector<std::vector<std::byte>> fromEach(size());
        group_.collective(
            rank_, &toEach,
            [&](std::span<const void* const> inputs) {
                for (int r = 0; r < size(); ++r)
                    fromEach[r] = (*static_cast<const std::vector<std::vector<std::byte>>*>(
                        inputs[r]))[rank_];
            },
            stopped_);
        return fromEach;
    }

    std::vector<std::byte> exchange(int peer, std::span<const std::byte> send) override {
        detail::checkRankArgument(*this, peer, "exchange", "peer");
        group_.post(kExchangeChannel, rank_, peer, send);
        return group_.take(kExchangeChannel, peer, rank_, stopped_);
    }

    void send(int to, std::span<const std::byte> bytes) override {
        detail::checkRankArgument(*this, to, "send", "destination");
        group_.post(kUserChannel, rank_, to, bytes);
    }

    std::vector<std::byte> receive(int from) override {
        detail::checkRankArgument(*this, from, "receive", "source");
        return group_.take(kUserChannel, from, rank_, stopped_);
    }

    void allReduce(std::span<double> values, ReduceOp op) override { reduceAll(values, op); }
    void allReduce(std::span<std::uint64_t> values, ReduceOp op) override { reduceAll(values, op); }

private:
    /// Reduces in rank order into a result of its own, written back once every rank has read.
    template <class T>
    void reduceAll(std::span<T> values, ReduceOp op) {
        std::span<const T> mine(values);
        std::vector<T> result;
        group_.collective(
            rank_, &mine,
            [&](std::span<const void* const> inputs) {
                for (int r = 0; r < size(); ++r) {
                    auto theirs = static_cast<const std::span<const T>*>(inputs[r]);
                    if (theirs->size() != mine.size())
                        throwError(ErrorKind::Argument, "",
                                   "allReduce: rank " + std::to_string(r) + " gave " +
                                       std::to_string(theirs->size()) + " values, rank " +
                                       std::to_string(rank_) + " " + std::to_string(mine.size()));
                }
                auto first = static_cast<const std::span<const T>*>(inputs[0]);
                result.assign(first->begin(), first->end());
                for (int r = 1; r < size(); ++r) {
                    auto theirs = static_cast<const std::span<const T>*>(inputs[r]);
                    for (std::size_t i = 0; i < result.size(); ++i)
                        result[i] = reduce(result[i], (*theirs)[i], op);
                }
            },
            stopped_);
        std::copy(result.begin(), result.end(), values.begin());
    }

    Group& group_;
    const int rank_;
    bool stopped_ = false;
};

/// The one rank of a group of one.
class SelfCommunicator final : public Communicator {
public:
    int rank() const override { return 0; }
    int size() const override { return 1; }
    void barrier() override {}
    void broadcast(std::vector<std::byte>&, int root) override {
        detail::checkRankArgument(*this, root, "broadcast", "root");
    }
    std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) override {
        return {std::vector<std::byte>(mine.begin(), mine.end())};
    }
    std::vector<std::vector<std::byte>> gather(std::span<const std::byte> mine, int root) override {
        detail::checkRankArgument(*this, root, "gather", "root");
        return {std::vector<std::byte>(mine.begin(), mine.end())};
    }
    std::vector<std::vector<std::byte>> allToAll(
        const std::vector<std::vector<std::byte>>& toEach) override {
        if (toEach.size() != 1)
            throwError(ErrorKind::Argument, "",
                       "allToAll: " + std::to_string(toEach.size()) + " messages for 1 rank");
        return toEach;
    }
    std::vector<std::byte> exchange(int peer, std::span<const std::byte> send) override {
        detail::checkRankArgument(*this, peer, "exchange", "peer");
        return {send.begin(), send.end()};
    }
    void send(int to, std::span<const std::byte> bytes) override {
        detail::checkRankArgument(*this, to, "send", "destination");
        queue_.emplace_back(bytes.begin(), bytes.end());
    }
    std::vector<std::byte> receive(int from) override {
        detail::checkRankArgument(*this, from, "receive", "source");
        if (queue_.empty())
            throwError(ErrorKind::Internal, "",
                       "rank 0 receives from itself with nothing sent: it would wait forever");
        std::vector<std::byte> message = std::move(queue_.front());
        queue_.pop_front();
        return message;
    }
    void allReduce(std::span<double>, ReduceOp) override {}
    void allReduce(std::span<std::uint64_t>, ReduceOp) override {}

private:
    std::deque<std::vector<std::byte>> queue_;  ///< messages sent to itself, oldest first
};

}  // namespace

void InProcessGroup::run(int ranks, const std::function<void(Communicator&)>& body) {
    if (ranks < 1)
        throwError(ErrorKind::Argument, "",
                   "an in-process group needs at least 1 rank, not " + std::to_string(ranks));
    Group group(ranks);
    std::vector<std::exception_ptr> failures(ranks);
    std::vector<char> stopped(ranks, 0);
    auto runRank = [&](int rank) {
        InProcessCommunicator comm(group, rank);
        try {
            body(comm);
        } catch (...) {
            failures[rank] = std::current_exception();
            stopped[rank] = comm.stopped();
        }
        group.end(rank, failures[rank]);
    };

    // Ranks 1..N-1 on threads of their own; a thread that cannot start fails its rank and every
    // later one, which stops the ranks already running.
    std::vector<std::thread> threads;
    threads.reserve(ranks - 1);
    bool started = true;
    for (int rank = 1; rank < ranks; ++rank) {
        try {
            threads.emplace_back(runRank, rank);
        } catch (...) {
            started = false;
            for (int r = rank; r < ranks; ++r) {
                failures[r] = std::current_exception();
                group.end(r, failures[r]);
            }
            break;
        }
    }
    if (started) {
        runRank(0);
    } else {
        group.end(0, nullptr);
    }
    for (std::thread& thread : threads) thread.join();

    // The lowest rank's own failure first, then the lowest rank stopped by another.
    for (int pass = 0; pass < 2; ++pass)
        for (int rank = 0; rank < ranks; ++rank)
            if (failures[rank] && (pass == 1 || !stopped[rank]))
                std::rethrow_exception(failures[rank]);
}

std::unique_ptr<Communicator> selfCommunicator() {
    return std::make_unique<SelfCommunicator>();
}

}  // namespace uvr

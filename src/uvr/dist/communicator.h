// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <optional>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

namespace uvr {

/// A type whose bytes are its value: what the value helpers send as they are.
template <class T>
concept TriviallyCopyable = std::is_trivially_copyable_v<T>;

/// An element-wise reduction of allReduce.
enum class ReduceOp { Sum, Min, Max };

/// A group of ranks that exchange bytes: MPI's ranks (mpi_communicator.h) or threads of one
/// process (in_process_communicator.h). Collectives must be called by every rank in the same
/// order; a rank's failure is shared with agree() at checkpoints.
class Communicator {
public:
    virtual ~Communicator() = default;

    /// This rank's number, 0 <= rank() < size().
    virtual int rank() const = 0;
    /// How many ranks the group holds (at least 1).
    virtual int size() const = 0;

    /// Returns once every rank has called it.
    virtual void barrier() = 0;
    /// Gives every rank root's bytes (the receivers' vector is resized to root's size).
    virtual void broadcast(std::vector<std::byte>& bytes, int root) = 0;
    /// Every rank's bytes on every rank, indexed by rank.
    virtual std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) = 0;
    /// Every rank's bytes, indexed by rank, on root; an empty vector on every other rank.
    virtual std::vector<std::vector<std::byte>> gather(std::span<const std::byte> mine,
                                                       int root) = 0;
    /// Sends toEach[r] to rank r (toEach.size() == size()); returns what each rank sent to this
    /// one, indexed by sender.
    virtual std::vector<std::vector<std::byte>> allToAll(
        const std::vector<std::vector<std::byte>>& toEach) = 0;
    /// allToAll into `fromEach`, and gather into `all` (resized; on root only): for a caller
    /// exchanging a frame every frame, each message's vector keeps its capacity from the last
    /// call where the implementation can (MPI), so no page is touched anew. The defaults call
    /// allToAll and gather.
    virtual void allToAllInto(const std::vector<std::vector<std::byte>>& toEach,
                              std::vector<std::vector<std::byte>>& fromEach) {
        fromEach = allToAll(toEach);
    }
    virtual void gatherInto(std::span<const std::byte> mine, int root,
                            std::vector<std::vector<std::byte>>& all) {
        all = gather(mine, root);
    }
    /// Sends to and receives from peer at once (deadlock-free, as MPI_Sendrecv; the two sizes may
    /// differ); peer calls exchange with this rank.
    virtual std::vector<std::byte> exchange(int peer, std::span<const std::byte> send) = 0;
    /// Sends bytes to rank `to`; messages between one pair arrive in the order sent. It may wait
    /// until `to` receives (as MPI_Send): two ranks sending to each other use exchange().
    virtual void send(int to, std::span<const std::byte> bytes) = 0;
    /// Receives the next message rank `from` sent to this rank with send().
    virtual std::vector<std::byte> receive(int from) = 0;
    /// Receives as receive() does, for a rank that may wait long for it (a viewer's rank
    /// between frames): MPI looks for the message every millisecond instead of spinning a core.
    virtual std::vector<std::byte> receiveIdle(int from) { return receive(from); }
    /// Reduces values element-wise over the ranks, in place, the result on every rank (every
    /// rank gives the same number of values).
    virtual void allReduce(std::span<double> values, ReduceOp op) = 0;
    /// Reduces unsigned 64-bit values element-wise over the ranks, in place (Sum wraps).
    virtual void allReduce(std::span<std::uint64_t> values, ReduceOp op) = 0;

    /// Fault agreement (collective): every rank passes its own failure or null; when any rank
    /// failed, every rank throws an Error of the lowest failing rank's kind with the message
    /// "rank R: <its message>" (an exception that is not a uvr::Error counts as Internal).
    void agree(std::exception_ptr failure);

    /// Gives every rank root's value of a trivially copyable T.
    template <TriviallyCopyable T>
    void broadcastValue(T& value, int root);
    /// Gives every rank root's values (the receivers' vector is resized).
    template <TriviallyCopyable T>
    void broadcastValue(std::vector<T>& values, int root);
    /// Every rank's value, indexed by rank, on every rank.
    template <TriviallyCopyable T>
    std::vector<T> allGatherValues(const T& mine);
    /// Every rank's values, indexed by rank, on every rank.
    template <TriviallyCopyable T>
    std::vector<std::vector<T>> allGatherValues(const std::vector<T>& mine);
};

/// Runs work() on this rank, then agrees with every rank on failures (Communicator::agree):
/// returns work's result when no rank failed, otherwise throws the lowest failing rank's error on
/// every rank.
template <class F>
auto agreeOn(Communicator& comm, F&& work) -> std::invoke_result_t<F&&>;

/// Copies bytes into values of a trivially copyable T (the byte count is a multiple of sizeof(T)).
template <TriviallyCopyable T>
std::vector<T> fromBytes(std::span<const std::byte> bytes);

/// Appends n values of a trivially copyable T to a message as bytes (fromBytes reads them).
template <TriviallyCopyable T>
void appendBytes(std::vector<std::byte>& out, const T* values, std::size_t n) {
    const auto* bytes = reinterpret_cast<const std::byte*>(values);
    out.insert(out.end(), bytes, bytes + n * sizeof(T));
}

// Implementation.

namespace detail {
/// Throws an Internal error: a message of `bytes` bytes does not hold values of `size` bytes.
[[noreturn]] void throwBadValueBytes(std::size_t bytes, std::size_t size);
/// Throws an Argument error unless 0 <= rank < comm.size(), naming the call and the argument.
void checkRankArgument(const Communicator& comm, int rank, const char* call, const char* what);
}  // namespace detail

template <TriviallyCopyable T>
std::vector<T> fromBytes(std::span<const std::byte> bytes) {
    if (bytes.size() % sizeof(T) != 0) detail::throwBadValueBytes(bytes.size(), sizeof(T));
    std::vector<T> values(bytes.size() / sizeof(T));
    if (!bytes.empty()) std::memcpy(values.data(), bytes.data(), bytes.size());
    return values;
}

template <TriviallyCopyable T>
void Communicator::broadcastValue(T& value, int root) {
    std::vector<std::byte> bytes(sizeof(T));
    std::memcpy(bytes.data(), &value, sizeof(T));
    broadcast(bytes, root);
    if (bytes.size() != sizeof(T)) detail::throwBadValueBytes(bytes.size(), sizeof(T));
    std::memcpy(&value, bytes.data(), sizeof(T));
}

template <TriviallyCopyable T>
void Communicator::broadcastValue(std::vector<T>& values, int root) {
    std::span<const std::byte> mine = std::as_bytes(std::span<const T>(values));
    std::vector<std::byte> bytes(mine.begin(), mine.end());
    broadcast(bytes, root);
    values = fromBytes<T>(bytes);
}

template <TriviallyCopyable T>
std::vector<T> Communicator::allGatherValues(const T& mine) {
    std::vector<std::vector<std::byte>> all =
        allGather(std::as_bytes(std::span<const T>(&mine, 1)));
    std::vector<T> values;
    values.reserve(all.size());
    for (const std::vector<std::byte>& bytes : all) {
        if (bytes.size() != sizeof(T)) detail::throwBadValueBytes(bytes.size(), sizeof(T));
        std::memcpy(&values.emplace_back(), bytes.data(), sizeof(T));
    }
    return values;
}

template <TriviallyCopyable T>
std::vector<std::vector<T>> Communicator::allGatherValues(const std::vector<T>& mine) {
    std::vector<std::vector<std::byte>> all = allGather(std::as_bytes(std::span<const T>(mine)));
    std::vector<std::vector<T>> values;
    values.reserve(all.size());
    for (const std::vector<std::byte>& bytes : all) values.push_back(fromBytes<T>(bytes));
    return values;
}

template <class F>
auto agreeOn(Communicator& comm, F&& work) -> std::invoke_result_t<F&&> {
    using Result = std::invoke_result_t<F&&>;
    static_assert(!std::is_reference_v<Result>, "agreeOn: work returns a value, not a reference");
    std::exception_ptr failure;
    if constexpr (std::is_void_v<Result>) {
        try {
            std::forward<F>(work)();
        } catch (...) {
            failure = std::current_exception();
        }
        comm.agree(failure);
    } else {
        std::optional<Result> result;
        try {
            result.emplace(std::forward<F>(work)());
        } catch (...) {
            failure = std::current_exception();
        }
        comm.agree(failure);
        return std::move(*result);
    }
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

// The checks every Communicator passes, run by each rank of a group: on the in-process group
// with 1, 2, 3, 5 and 8 ranks (src/uvr/dist/in_process_communicator_test.cpp) and on MPI's ranks
// under mpirun (mpi_communicator_test.cpp). Each rank calls the same collectives in the same
// order whatever it finds: the checks use EXPECT (never ASSERT or an early return), so a failed
// check cannot leave the other ranks waiting.

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/dist/communicator.h"

namespace uvr::testing {

/// A buffer of more than 1 MiB (an odd size, so pieces of any size end short).
inline constexpr std::size_t kLargeMessage = (std::size_t(1) << 20) + 13;

/// Byte i of pattern(seed, n): it depends on seed and on i (bytes 256 and 2^24 apart differ).
inline std::byte patternByte(std::uint64_t seed, std::size_t i) {
    return std::byte((seed * 131 + i * 7 + (i >> 8) + (i >> 24)) & 0xff);
}

/// n bytes that depend on seed and on each byte's position.
inline std::vector<std::byte> pattern(std::uint64_t seed, std::size_t n) {
    std::vector<std::byte> bytes(n);
    for (std::size_t i = 0; i < n; ++i) bytes[i] = patternByte(seed, i);
    return bytes;
}

/// A size that varies with (a, b): 0 for some, small for most, large for one.
inline std::size_t varyingSize(int a, int b) {
    if ((a + 2 * b) % 4 == 1) return 0;
    if (a == 0 && b == 1) return kLargeMessage;
    return std::size_t(a * 37 + b * 11) % 101 + 1;
}

/// Whether `bytes` equals pattern(seed, n), without printing a megabyte when it does not.
inline ::testing::AssertionResult isPattern(const std::vector<std::byte>& bytes, std::uint64_t seed,
                                            std::size_t n) {
    if (bytes.size() != n)
        return ::testing::AssertionFailure() << bytes.size() << " bytes, expected " << n;
    for (std::size_t i = 0; i < n; ++i)
        if (bytes[i] != patternByte(seed, i))
            return ::testing::AssertionFailure() << "byte " << i << " of " << n << " differs";
    return ::testing::AssertionSuccess();
}

/// broadcast from every root, with root-dependent sizes (empty and large among them), into
/// receivers' vectors of other sizes.
inline void checkBroadcast(Communicator& comm) {
    const int me = comm.rank();
    for (int root = 0; root < comm.size(); ++root) {
        std::size_t n = root == comm.size() - 1 ? kLargeMessage : std::size_t(root % 3) * 50;
        std::vector<std::byte> bytes = me == root ? pattern(root + 1, n) : pattern(99, 7);
        comm.broadcast(bytes, root);
        EXPECT_TRUE(isPattern(bytes, root + 1, n)) << "rank " << me << ", root " << root;
    }
}

/// allGather with every rank's own size (empty and large among them).
inline void checkAllGather(Communicator& comm) {
    const int me = comm.rank();
    for (int round = 0; round < 2; ++round) {
        std::vector<std::vector<std::byte>> all =
            comm.allGather(pattern(me + 10 * round, varyingSize(me, round)));
        EXPECT_EQ(int(all.size()), comm.size());
        for (int r = 0; r < int(all.size()); ++r)
            EXPECT_TRUE(isPattern(all[r], r + 10 * round, varyingSize(r, round)))
                << "rank " << me << " holds rank " << r << "'s part";
    }
}

/// gather onto every root in turn: everything on the root, nothing elsewhere.
inline void checkGather(Communicator& comm) {
    const int me = comm.rank();
    for (int root = 0; root < comm.size(); ++root) {
        std::vector<std::vector<std::byte>> all =
            comm.gather(pattern(me * 3 + root, varyingSize(me, root)), root);
        if (me != root) {
            EXPECT_TRUE(all.empty()) << "rank " << me << ", root " << root;
            continue;
        }
        EXPECT_EQ(int(all.size()), comm.size());
        for (int r = 0; r < int(all.size()); ++r)
            EXPECT_TRUE(isPattern(all[r], r * 3 + root, varyingSize(r, root)))
                << "root " << root << " holds rank " << r << "'s part";
    }
    // gatherInto twice onto rank 0, into buffers that held other bytes: as gather.
    std::vector<std::vector<std::byte>> into(comm.size() + 1, pattern(99, kLargeMessage));
    for (int round = 1; round <= 2; ++round) {
        comm.gatherInto(pattern(me * 5 + round, varyingSize(me + round, 0)), 0, into);
        if (me != 0) continue;
        EXPECT_EQ(int(into.size()), comm.size());
        for (int r = 0; r < int(into.size()); ++r)
            EXPECT_TRUE(isPattern(into[r], r * 5 + round, varyingSize(r + round, 0)))
                << "gatherInto, round " << round << ": rank " << r << "'s part";
    }
}

/// allToAll with a size per (sender, receiver) pair (empty and large among them).
inline void checkAllToAll(Communicator& comm) {
    const int me = comm.rank(), n = comm.size();
    std::vector<std::vector<std::byte>> toEach(n);
    for (int r = 0; r < n; ++r) toEach[r] = pattern(me * 100 + r, varyingSize(me, r));
    std::vector<std::vector<std::byte>> fromEach = comm.allToAll(toEach);
    EXPECT_EQ(int(fromEach.size()), n);
    for (int s = 0; s < int(fromEach.size()); ++s)
        EXPECT_TRUE(isPattern(fromEach[s], s * 100 + me, varyingSize(s, me)))
            << "rank " << me << " from rank " << s;
    // allToAllInto twice into buffers that held other bytes (more of them, and more buffers),
    // the second call's messages of other sizes: each time what allToAll gives.
    std::vector<std::vector<std::byte>> into(n + 1, pattern(99, kLargeMessage));
    for (int round = 1; round <= 2; ++round) {
        for (int r = 0; r < n; ++r)
            toEach[r] = pattern(me * 100 + r + round, varyingSize(me + round, r));
        comm.allToAllInto(toEach, into);
        EXPECT_EQ(int(into.size()), n);
        for (int s = 0; s < int(into.size()); ++s)
            EXPECT_TRUE(isPattern(into[s], s * 100 + me + round, varyingSize(s + round, me)))
                << "allToAllInto, round " << round << ": rank " << me << " from rank " << s;
    }
}

/// exchange between the pairs (r, r xor mask) for masks 1, 2, 4 (a rank without a partner
/// exchanges with itself), sizes differing in the two directions.
inline void checkExchange(Communicator& comm) {
    const int me = comm.rank();
    for (int mask = 1; mask <= 4; mask *= 2) {
        int peer = (me ^ mask) < comm.size() ? me ^ mask : me;
        std::size_t mineSize = varyingSize(me, mask), theirSize = varyingSize(peer, mask);
        if (mask == 1 && me == 0) mineSize = kLargeMessage;
        if (mask == 1 && peer == 0) theirSize = kLargeMessage;
        std::vector<std::byte> received = comm.exchange(peer, pattern(me * 7 + mask, mineSize));
        EXPECT_TRUE(isPattern(received, peer * 7 + mask, theirSize))
            << "rank " << me << " from rank " << peer << ", mask " << mask;
    }
}

/// send/receive in order: three messages (one empty, one large) around the ring, rank 0 sending
/// first and every other rank receiving first (so no two ranks wait to send to each other); then
/// four messages from every rank to rank 0, received sender by sender from the last.
inline void checkSendReceive(Communicator& comm) {
    const int me = comm.rank(), n = comm.size();
    const std::size_t sizes[3] = {5, 0, kLargeMessage};
    auto sendRing = [&] {
        for (int i = 0; i < 3; ++i) comm.send((me + 1) % n, pattern(me * 10 + i, sizes[i]));
    };
    auto receiveRing = [&] {
        int from = (me + n - 1) % n;
        for (int i = 0; i < 3; ++i)
            EXPECT_TRUE(isPattern(comm.receive(from), from * 10 + i, sizes[i]))
                << "rank " << me << ", message " << i << " from rank " << from;
    };
    if (me == 0) {
        sendRing();
        receiveRing();
    } else {
        receiveRing();
        sendRing();
    }

    if (me != 0)
        for (int i = 0; i < 4; ++i) comm.send(0, pattern(me * 1000 + i, std::size_t(i * me)));
    if (me == 0) {
        for (int from = n - 1; from >= 1; --from)
            for (int i = 0; i < 4; ++i) {
                EXPECT_TRUE(isPattern(comm.receive(from), from * 1000 + i, std::size_t(i * from)))
                    << "message " << i << " from rank " << from;
            }
    }
    comm.barrier();
}

/// allReduce of doubles and of unsigned 64-bit values (above 2^32), each operation, empty too;
/// `count` values per rank.
inline void checkAllReduce(Communicator& comm, std::size_t count = 1000) {
    const int me = comm.rank(), n = comm.size();
    for (ReduceOp op : {ReduceOp::Sum, ReduceOp::Min, ReduceOp::Max}) {
        std::vector<double> values(count);
        for (std::size_t i = 0; i < count; ++i) values[i] = me * 10.0 + double(i) + 0.5;
        comm.allReduce(values, op);
        std::size_t wrong = 0;
        for (std::size_t i = 0; i < count; ++i) {
            double expected = op == ReduceOp::Sum   ? 10.0 * n * (n - 1) / 2 + n * (i + 0.5)
                              : op == ReduceOp::Min ? double(i) + 0.5
                                                    : (n - 1) * 10.0 + double(i) + 0.5;
            wrong += values[i] != expected;
        }
        EXPECT_EQ(wrong, 0u) << "rank " << me << ", operation " << int(op);

        std::vector<std::uint64_t> counts(count);
        for (std::size_t i = 0; i < count; ++i) counts[i] = (std::uint64_t(me + 1) << 40) + i;
        comm.allReduce(counts, op);
        wrong = 0;
        for (std::size_t i = 0; i < count; ++i) {
            std::uint64_t expected =
                op == ReduceOp::Sum ? (std::uint64_t(n * (n + 1) / 2) << 40) + std::uint64_t(n) * i
                : op == ReduceOp::Min ? (std::uint64_t(1) << 40) + i
                                      : (std::uint64_t(n) << 40) + i;
            wrong += counts[i] != expected;
        }
        EXPECT_EQ(wrong, 0u) << "rank " << me << ", operation " << int(op);

        std::vector<double> none;
        comm.allReduce(none, op);
    }
}

/// The value helpers: broadcastValue of a struct and of a vector, allGatherValues of both.
inline void checkValueHelpers(Communicator& comm) {
    struct Box {
        double lo[3], hi[3];
        std::int32_t rank;
    };
    const int me = comm.rank(), n = comm.size();
    Box box = {{me * 1.0, 0, 0}, {me + 1.0, 1, 1}, me};
    comm.broadcastValue(box, n - 1);
    EXPECT_EQ(box.rank, n - 1);
    EXPECT_EQ(box.hi[0], double(n));

    std::vector<std::int64_t> ids(std::size_t(me) + 2, me);
    comm.broadcastValue(ids, 0);
    EXPECT_EQ(ids, std::vector<std::int64_t>(2, 0)) << "rank " << me;

    std::vector<float> ranks = comm.allGatherValues(float(me) * 0.5f);
    EXPECT_EQ(int(ranks.size()), n);
    for (int r = 0; r < int(ranks.size()); ++r) EXPECT_EQ(ranks[r], float(r) * 0.5f);

    std::vector<std::vector<std::uint32_t>> lists =
        comm.allGatherValues(std::vector<std::uint32_t>(std::size_t(me), std::uint32_t(me)));
    EXPECT_EQ(int(lists.size()), n);
    for (int r = 0; r < int(lists.size()); ++r)
        EXPECT_EQ(lists[r], std::vector<std::uint32_t>(std::size_t(r), std::uint32_t(r)));
}

/// agree() and agreeOn(): nothing thrown when no rank fails; otherwise every rank throws the
/// lowest failing rank's kind and message ("rank 2: ..." where there are 3 ranks or more).
inline void checkAgree(Communicator& comm) {
    const int me = comm.rank(), n = comm.size();
    EXPECT_NO_THROW(comm.agree(nullptr));
    EXPECT_EQ(agreeOn(comm, [&] { return me * 2; }), me * 2);

    const int failing = std::min(2, n - 1);
    std::exception_ptr failure;
    if (me == failing)
        failure = std::make_exception_ptr(Error(ErrorKind::Parse, "part.vtu: byte 12: truncated"));
    else if (me > failing)
        failure = std::make_exception_ptr(Error(ErrorKind::Io, "a later rank's failure"));
    try {
        comm.agree(failure);
        ADD_FAILURE() << "rank " << me << ": agree() did not throw";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Parse) << "rank " << me;
        EXPECT_EQ(std::string(e.what()),
                  "rank " + std::to_string(failing) + ": part.vtu: byte 12: truncated")
            << "rank " << me;
    }

    try {
        agreeOn(comm, [&] {
            if (me == n - 1) throw std::runtime_error("not a uvr error");
        });
        ADD_FAILURE() << "rank " << me << ": agreeOn() did not throw";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Internal) << "rank " << me;
        EXPECT_EQ(std::string(e.what()), "rank " + std::to_string(n - 1) + ": not a uvr error");
    }
}

/// Every check above, in one order on every rank.
inline void checkEveryCollective(Communicator& comm, int expectedSize) {
    EXPECT_EQ(comm.size(), expectedSize);
    EXPECT_GE(comm.rank(), 0);
    EXPECT_LT(comm.rank(), comm.size());
    comm.barrier();
    checkBroadcast(comm);
    checkAllGather(comm);
    checkGather(comm);
    checkAllToAll(comm);
    checkExchange(comm);
    checkSendReceive(comm);
    checkAllReduce(comm);
    checkValueHelpers(comm);
    checkAgree(comm);
    comm.barrier();
}

}  // namespace uvr::testing

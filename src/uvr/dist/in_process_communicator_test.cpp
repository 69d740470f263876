// SPDX-License-Identifier: MIT
// The in-process group: every collective with 1, 2, 3, 5 and 8 ranks (tests/communicator_checks.h),
// failures that stop the group instead of hanging it, and the communicator of one rank alone.
#include "uvr/dist/in_process_communicator.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "communicator_checks.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using testing::checkEveryCollective;
using testing::kLargeMessage;
using testing::pattern;

/// Runs body on a group and returns the Error run() rethrows (fails the test when it throws
/// none or another type).
Error runExpectingError(int ranks, const std::function<void(Communicator&)>& body) {
    try {
        InProcessGroup::run(ranks, body);
    } catch (const Error& e) {
        return e;
    }
    ADD_FAILURE() << "InProcessGroup::run did not throw a uvr::Error";
    return Error(ErrorKind::Internal, "");
}

class InProcessCommunicator : public ::testing::TestWithParam<int> {};

TEST_P(InProcessCommunicator, EveryCollectiveGivesEveryRankExactlyItsBytes) {
    const int ranks = GetParam();
    std::atomic<int> bodies = 0;
    InProcessGroup::run(ranks, [&](Communicator& comm) {
        ++bodies;
        checkEveryCollective(comm, ranks);
    });
    EXPECT_EQ(bodies, ranks);
}

TEST_P(InProcessCommunicator, ManyCollectivesInARowKeepTheirGenerationsApart) {
    // Fast ranks enter the next collective while slow ones still leave the last.
    const int ranks = GetParam();
    InProcessGroup::run(ranks, [&](Communicator& comm) {
        std::size_t wrong = 0;
        for (int i = 0; i < 300; ++i) {
            std::vector<std::uint64_t> value = {std::uint64_t(comm.rank() + i)};
            comm.allReduce(value, ReduceOp::Max);
            wrong += value[0] != std::uint64_t(ranks - 1 + i);
            std::vector<std::vector<std::byte>> all = comm.allGather(pattern(i, comm.rank()));
            for (int r = 0; r < ranks; ++r) wrong += all[r] != pattern(i, r);
            if (i % 7 == 0) comm.barrier();
        }
        EXPECT_EQ(wrong, 0u) << "rank " << comm.rank();
    });
}

TEST_P(InProcessCommunicator, ARankThrowingStopsTheOthersWaitingInACollective) {
    // Rank 1 (or 0 alone) fails before the second collective; the others wait in it, wake and
    // throw "rank 1 failed: ..."; run() returns and rethrows rank 1's own error.
    const int ranks = GetParam();
    const int failing = std::min(1, ranks - 1);
    std::mutex mutex;
    std::vector<std::string> woken;
    Error e = runExpectingError(ranks, [&](Communicator& comm) {
        comm.barrier();
        if (comm.rank() == failing) throwError(ErrorKind::Io, "part_1.vtu", "cannot open");
        try {
            comm.allGather(pattern(1, kLargeMessage));
            comm.barrier();
        } catch (const Error& stop) {
            std::lock_guard lock(mutex);
            woken.push_back(stop.what());
            throw;
        }
    });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_STREQ(e.what(), "part_1.vtu: cannot open");
    EXPECT_EQ(int(woken.size()), ranks - 1);
    for (const std::string& message : woken)
        EXPECT_EQ(message, "rank " + std::to_string(failing) + " failed: part_1.vtu: cannot open");
}

TEST_P(InProcessCommunicator, ARankThrowingStopsTheOthersWaitingToReceiveFromIt) {
    // Not a uvr::Error: run() rethrows it as it is; the woken ranks name its message.
    const int ranks = GetParam();
    std::mutex mutex;
    std::vector<std::string> woken;
    EXPECT_THROW(InProcessGroup::run(ranks,
                                     [&](Communicator& comm) {
                                         if (comm.rank() == ranks - 1)
                                             throw std::runtime_error("out of disk");
                                         try {
                                             comm.receive(ranks - 1);
                                         } catch (const Error& stop) {
                                             std::lock_guard lock(mutex);
                                             woken.push_back(stop.what());
                                             throw;
                                         }
                                     }),
                 std::runtime_error);
    EXPECT_EQ(int(woken.size()), ranks - 1);
    for (const std::string& message : woken)
        EXPECT_EQ(message, "rank " + std::to_string(ranks - 1) + " failed: out of disk");
}

TEST_P(InProcessCommunicator, ARankReturningEarlyEndsTheOthersWithAnError) {
    const int ranks = GetParam();
    if (ranks == 1) GTEST_SKIP() << "needs a second rank";
    Error e = runExpectingError(ranks, [&](Communicator& comm) {
        if (comm.rank() == 0) return;
        comm.barrier();
    });
    EXPECT_EQ(e.kind(), ErrorKind::Internal);
    EXPECT_NE(std::string(e.what()).find("rank 0 ended without joining a collective"),
              std::string::npos)
        << e.what();
}

TEST_P(InProcessCommunicator, AgreeTurnsOneRanksFailureIntoOneErrorOnEveryRank) {
    // The case: one rank cannot read its part; every rank ends with the same line.
    const int ranks = GetParam();
    const int failing = std::min(2, ranks - 1);
    std::atomic<int> agreed = 0;
    Error e = runExpectingError(ranks, [&](Communicator& comm) {
        try {
            agreeOn(comm, [&] {
                if (comm.rank() == failing)
                    throwError(ErrorKind::Io, "part_2.vtu", "No such file or directory");
            });
        } catch (const Error& thrown) {
            if (thrown.kind() == ErrorKind::Io &&
                std::string(thrown.what()) ==
                    "rank " + std::to_string(failing) + ": part_2.vtu: No such file or directory")
                ++agreed;
            throw;
        }
    });
    EXPECT_EQ(agreed, ranks);
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_EQ(std::string(e.what()),
              "rank " + std::to_string(failing) + ": part_2.vtu: No such file or directory");
}

TEST_P(InProcessCommunicator, BadRanksAndCountsAreArgumentErrors) {
    const int ranks = GetParam();
    InProcessGroup::run(ranks, [&](Communicator& comm) {
        std::vector<std::byte> bytes;
        EXPECT_THROW(comm.broadcast(bytes, ranks), Error);
        EXPECT_THROW(comm.gather({}, -1), Error);
        EXPECT_THROW(comm.send(ranks, {}), Error);
        EXPECT_THROW(comm.receive(-1), Error);
        EXPECT_THROW(comm.exchange(ranks + 3, {}), Error);
        try {
            comm.allToAll(std::vector<std::vector<std::byte>>(ranks + 1));
            ADD_FAILURE() << "allToAll with too many messages";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
        }
        // Different value counts: every rank sees every count and throws.
        std::vector<double> values(comm.rank() == 0 ? 2 : 3);
        if (ranks > 1) {
            EXPECT_THROW(comm.allReduce(values, ReduceOp::Sum), Error);
        }
        comm.barrier();
    });
}

INSTANTIATE_TEST_SUITE_P(Ranks, InProcessCommunicator, ::testing::Values(1, 2, 3, 5, 8));

TEST(InProcessGroup, RunNeedsAtLeastOneRank) {
    Error e = runExpectingError(0, [](Communicator&) {});
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
}

TEST(InProcessGroup, RunRethrowsTheLowestFailingRanksOwnError) {
    Error e = runExpectingError(5, [](Communicator& comm) {
        if (comm.rank() == 3) throwError(ErrorKind::Parse, "", "rank three");
        if (comm.rank() == 4) throwError(ErrorKind::Io, "", "rank four");
        comm.barrier();  // ranks 0-2 are stopped here: their errors are not their own
    });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_STREQ(e.what(), "rank three");
}

TEST(InProcessGroup, RankZeroRunsOnTheCallingThread) {
    const std::thread::id caller = std::this_thread::get_id();
    std::atomic<int> onCaller = 0;
    InProcessGroup::run(4, [&](Communicator& comm) {
        if (std::this_thread::get_id() == caller) onCaller += 1 + comm.rank() * 10;
    });
    EXPECT_EQ(onCaller, 1);
}

TEST(SelfCommunicator, EveryCollectiveIsItsOwnRanksBytes) {
    std::unique_ptr<Communicator> self = selfCommunicator();
    checkEveryCollective(*self, 1);
}

TEST(SelfCommunicator, ReceivingWithNothingSentIsAnErrorNotAHang) {
    std::unique_ptr<Communicator> self = selfCommunicator();
    EXPECT_THROW(self->receive(0), Error);
    EXPECT_THROW(self->send(1, {}), Error);
    self->send(0, pattern(3, 4));
    self->send(0, pattern(4, 0));
    EXPECT_EQ(self->receive(0), pattern(3, 4));
    EXPECT_EQ(self->receive(0), pattern(4, 0));
    EXPECT_THROW(self->receive(0), Error);
}

TEST(SelfCommunicator, AgreeRethrowsItsOwnFailureWithItsRank) {
    std::unique_ptr<Communicator> self = selfCommunicator();
    try {
        agreeOn(*self, []() -> int { throwError(ErrorKind::Validation, "", "cell 7 inverted"); });
        ADD_FAILURE() << "agreeOn did not throw";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Validation);
        EXPECT_STREQ(e.what(), "rank 0: cell 7 inverted");
    }
}

}  // namespace
}  // namespace uvr

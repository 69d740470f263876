// SPDX-License-Identifier: MIT
// The MPI communicator: the checks every communicator passes (tests/communicator_checks.h) on
// mpiWorld() and on a communicator whose messages go in pieces of 1000 bytes. They run only under
// an MPI launcher (the CTest cases mpi.communicator_2_ranks and _4_ranks: mpirun -n 2 and -n 4
// with --gtest_filter='MpiCommunicator.*'); a plain run of uvr_tests skips them and never
// initialises MPI.
#include "uvr/dist/mpi_communicator.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "communicator_checks.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using testing::checkEveryCollective;

/// Skips the test unless this process is one of several started by an MPI launcher.
#define UVR_SKIP_UNLESS_UNDER_MPI()                                                      \
    do {                                                                                 \
        if (!builtWithMpi()) GTEST_SKIP() << "this uvr was built without MPI";           \
        if (!launchedUnderMpi()) GTEST_SKIP() << "not started by mpirun (ctest -L mpi)"; \
    } while (0)

TEST(MpiCommunicator, EveryCollectiveGivesEveryRankExactlyItsBytes) {
    UVR_SKIP_UNLESS_UNDER_MPI();
    Communicator& world = mpiWorld();
    int size = 0;
    ASSERT_NO_THROW(size = world.size());
    checkEveryCollective(world, size);
}

TEST(MpiCommunicator, MessagesInManyPiecesArriveWhole) {
    // Pieces of 1000 bytes: the path a message over 1 GiB takes, on buffers of 1 MiB.
    UVR_SKIP_UNLESS_UNDER_MPI();
    std::unique_ptr<Communicator> comm = makeMpiCommunicator(1000);
    checkEveryCollective(*comm, mpiWorld().size());
    testing::checkAllReduce(*comm, 100000);  // 100 pieces of 125 values
}

TEST(MpiCommunicator, MessagesOver2GiBArriveWhole) {
    // 2^31 + 5 bytes exchanged, sent and broadcast: about 4 GiB per rank, so only on request.
    UVR_SKIP_UNLESS_UNDER_MPI();
    if (std::getenv("UVR_TEST_MPI_HUGE") == nullptr)
        GTEST_SKIP() << "set UVR_TEST_MPI_HUGE=1 to move 2 GiB messages (4 GiB per rank)";
    Communicator& world = mpiWorld();
    const std::size_t n = (std::size_t(1) << 31) + 5;
    const int me = world.rank(), peer = me ^ 1;
    if (peer < world.size()) {
        std::vector<std::byte> received = world.exchange(peer, testing::pattern(me, n));
        EXPECT_TRUE(testing::isPattern(received, peer, n)) << "rank " << me;
        if (me < peer) world.send(peer, testing::pattern(me + 10, n));
        received = world.receive(peer);
        EXPECT_TRUE(testing::isPattern(received, peer + 10, n)) << "rank " << me;
        if (me > peer) world.send(peer, testing::pattern(me + 10, n));
    }
    std::vector<std::byte> bytes = me == 0 ? testing::pattern(20, n) : std::vector<std::byte>();
    world.broadcast(bytes, 0);
    EXPECT_TRUE(testing::isPattern(bytes, 20, n)) << "rank " << me;
}

TEST(MpiCommunicator, PiecesOutsideOneToIntMaxAreArgumentErrors) {
    UVR_SKIP_UNLESS_UNDER_MPI();
    EXPECT_THROW(makeMpiCommunicator(0), Error);
    EXPECT_THROW(makeMpiCommunicator(std::size_t(1) << 31), Error);
}

}  // namespace
}  // namespace uvr

#undef UVR_SKIP_UNLESS_UNDER_MPI  // file-local: the unity build joins test files

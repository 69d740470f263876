// SPDX-License-Identifier: MIT
// The MPI functions of a build without MPI (UVR_ENABLE_MPI=OFF).
#include "uvr/core/error.h"
#include "uvr/dist/mpi_communicator.h"

namespace uvr {

namespace {

[[noreturn]] void throwNoMpi() {
    throwError(ErrorKind::Unsupported, "",
               "this uvr was built without MPI (install libopenmpi-dev and rebuild): it cannot "
               "run as one of several ranks under mpirun");
}

}  // namespace

bool builtWithMpi() {
    return false;
}

Communicator& mpiWorld() {
    throwNoMpi();
}

std::unique_ptr<Communicator> makeMpiCommunicator(std::size_t) {
    throwNoMpi();
}

}  // namespace uvr

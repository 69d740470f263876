// SPDX-License-Identifier: MIT
// launchedUnderMpi, the same with or without MPI in the build.
#include <cstdlib>

#include "uvr/dist/mpi_communicator.h"

namespace uvr {

bool launchedUnderMpi() {
    // Open MPI's mpirun; PMIx (Open MPI, srun --mpi=pmix); PMI (MPICH's and Intel MPI's Hydra,
    // srun --mpi=pmi2); MVAPICH2; Cray PALS.
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE",
                             "MV2_COMM_WORLD_SIZE", "PALS_RANKID"})
        if (std::getenv(name) != nullptr) return true;
    return false;
}

}  // namespace uvr

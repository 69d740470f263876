// SPDX-License-Identifier: MIT
// launchedUnderMpi and the ranks' GPUs, the same with or without MPI in the build.
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>

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

int localRankFromEnvironment() {
    // Open MPI, Slurm, MPICH's Hydra, MVAPICH2, Cray PALS.
    for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID", "MPI_LOCALRANKID",
                             "MV2_COMM_WORLD_LOCAL_RANK", "PALS_LOCAL_RANKID"})
        if (const char* v = std::getenv(name)) {
            char* end = nullptr;
            const long rank = std::strtol(v, &end, 10);
            if (end != v && *end == '\0' && rank >= 0 && rank < (1L << 20))
                return static_cast<int>(rank);
        }
    return -1;
}

std::string pinGpuToLocalRank() {
    if (std::getenv("CUDA_VISIBLE_DEVICES") != nullptr) return "";
    const int local = localRankFromEnvironment();
    if (local < 0) return "";
    // The NVIDIA driver's device nodes /dev/nvidia0, /dev/nvidia1, ... (counted without
    // starting CUDA, which would then see them all).
    int gpus = 0;
    std::error_code ec;
    const std::regex node("nvidia[0-9]+");
    for (const auto& entry : std::filesystem::directory_iterator("/dev", ec))
        if (std::regex_match(entry.path().filename().string(), node)) ++gpus;
    if (gpus < 2) return "";
    const std::string device = std::to_string(local % gpus);
    setenv("CUDA_VISIBLE_DEVICES", device.c_str(), 0);
    return device;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <memory>

#include "uvr/dist/communicator.h"

namespace uvr {

/// The largest piece one MPI call moves (1 GiB): MPI's counts are int, so a larger message goes
/// in pieces.
inline constexpr std::size_t kMpiMaxChunkBytes = std::size_t(1) << 30;

/// Whether this uvr was built with MPI (UVR_ENABLE_MPI).
bool builtWithMpi();

/// Whether the environment says an MPI launcher (mpirun, mpiexec, srun) started this process
/// (OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_RANK, PMI_SIZE, ...); a plain start is never one.
bool launchedUnderMpi();

/// This process's rank among the ranks of its node, as the launcher says (Open MPI's
/// OMPI_COMM_WORLD_LOCAL_RANK, Slurm's SLURM_LOCALID, ...); -1 when none says.
int localRankFromEnvironment();

/// One GPU per rank of a node: unless CUDA_VISIBLE_DEVICES is set, sets it to the local rank
/// modulo the node's GPUs (counted from the driver's /dev/nvidiaN nodes) when there are two or
/// more, before CUDA starts. Returns the device chosen, or "" when it left the setting alone.
/// Call before anything touches CUDA.
std::string pinGpuToLocalRank();

/// The communicator over every process of MPI_COMM_WORLD (a duplicate of it). The first call
/// initialises MPI (MPI_THREAD_FUNNELED: only the thread that made it calls MPI) unless someone
/// else did, and then finalises it at exit; without MPI in this build it throws Unsupported.
Communicator& mpiWorld();

/// A new communicator over mpiWorld()'s ranks (collective: every rank calls it) whose messages
/// go in pieces of at most maxChunkBytes (1 <= maxChunkBytes <= INT_MAX; tests use small ones).
std::unique_ptr<Communicator> makeMpiCommunicator(std::size_t maxChunkBytes = kMpiMaxChunkBytes);

}  // namespace uvr

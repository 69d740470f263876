// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/lbvh.h"
#include "uvr/accel/macro_grid.h"
#include "uvr/accel/seed_grid.h"

namespace uvr {

/// Below this many tetrahedra `--build-device auto` builds on the CPU even when rendering on CUDA:
/// the CPU's SAH trees take under a second there and are a few percent faster to query than the
/// linear BVHs (measured on an H100, docs/PERFORMANCE.md).
inline constexpr std::uint64_t kAutoGpuBuildTets = 4000000;

/// Builds the LBVHs of lbvh.h on the GPU: uploads the points, tetrahedra and primitive list,
/// sorts Morton keys with CUB's radix sort, builds every inner node and leaf in parallel, and
/// downloads the nodes and leaf order; the same trees as buildLbvhCpu. Device memory is freed on
/// return. Throws Error(Resource) naming the need and the free memory when it does not fit,
/// Error(Unsupported) when uvr was built without CUDA or no device is present.
LbvhResult buildLbvhCuda(const LbvhInput& input);

/// Builds the k-d tree of buildKdPartitions on the GPU, one level at a time (every node of a
/// level at once: bounds, a sort of (node, centre) keys for the medians, scans for the sides): the
/// same splits, leaves and cell lists as the CPU's build, numbered breadth-first; below
/// options.root's node when set, as the CPU's. Throws as buildLbvhCuda does.
KdTree buildKdTreeCuda(const TetMesh& mesh, const KdBuildOptions& options,
                       const FractionFn& progress = {});

/// The order of cells by 63-bit keys (a CellOrderSorter for sortCellsSpatially): CUB's stable
/// radix sort of (key, position) pairs, the same order as the CPU's sort. Throws as
/// buildLbvhCuda does.
void sortCellKeysCuda(const std::uint64_t* keys, std::uint64_t count, std::uint32_t* order);

/// Finds the face neighbours of buildTetNeighbors on the GPU (points welded on the CPU, or
/// `welded` when given: coincidentPointIds(mesh.points), found earlier; faces counted,
/// scattered into their smallest vertex's bucket and paired there, in passes over vertex ranges
/// when they do not all fit, or of at most facesPerPass faces when it is not 0): the same
/// table. Throws as buildLbvhCuda does.
std::vector<std::uint32_t> buildTetNeighborsCuda(
    const TetMesh& mesh, const FractionFn& progress = {}, std::uint64_t facesPerPass = 0,
    const std::vector<std::uint32_t>* welded = nullptr);

/// Builds the seed grids of buildSeedGrids on the GPU (one block per partition, seed keys kept
/// by atomic minima): the same grids and seeds. Throws as buildLbvhCuda does.
SeedGrids buildSeedGridsCuda(const TetMesh& mesh, const KdPartitions& kd, float tetsPerCell,
                             const FractionFn& progress = {});

/// Builds the macrocell grids of buildMacroGrids and the gradient spreads of
/// partitionGradientSpread on the GPU (one block per partition; ranges, gradient boxes and flags
/// kept by atomic minima, maxima and ors): the same values, zeros possibly of the other sign.
/// Throws as buildLbvhCuda does.
MacroBuild buildMacroGridsCuda(const TetMesh& mesh, const KdPartitions& kd,
                               const std::vector<std::uint32_t>& neighbors, float tetsPerCell,
                               const FractionFn& progress = {});

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/lbvh.h"

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
/// same splits, leaves and cell lists as the CPU's build, numbered breadth-first. Throws as
/// buildLbvhCuda does.
KdTree buildKdTreeCuda(const TetMesh& mesh, const KdBuildOptions& options);

}  // namespace uvr

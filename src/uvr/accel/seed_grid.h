// SPDX-License-Identifier: MIT
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/point_locator.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/host_device.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// One partition's uniform grid over its shrunk box (40 bytes).
struct PartitionGrid {
    Vec3f lo;                 ///< grid origin (the partition box's low corner)
    Vec3f cellsPerUnit;       ///< grid cells per world unit on each axis
    std::uint32_t dims[3]{};  ///< cells on each axis (>= 1)
    std::uint32_t first = 0;  ///< index of the grid's first cell in the seed array
};

/// Plain-data view of the seed grids for CPU and GPU kernels.
struct SeedGridView {
    const PartitionGrid* grids = nullptr;  ///< one per k-d partition; null: no seed grids
    const std::uint32_t* seeds = nullptr;  ///< per grid cell: a tetrahedron id or kNoTet

    /// A tetrahedron of `partition` close to p to start a walk from, or kNoTet when no cell of
    /// the partition overlaps p's grid cell (so none contains p). Exact for p in the partition's
    /// box: cell indices are monotonic in p and clamped, so a tetrahedron containing p has p's
    /// grid cell inside the range of its own bounds.
    UVR_HOST_DEVICE std::uint32_t seed(std::uint32_t partition, Vec3f p) const {
        const PartitionGrid& g = grids[partition];
        std::uint32_t i[3];
        for (int a = 0; a < 3; ++a) i[a] = cellIndex(g, a, p[a]);
        return seeds[g.first + (i[2] * g.dims[1] + i[1]) * g.dims[0] + i[0]];
    }

    /// Grid cell index of coordinate x on axis a, clamped to the grid (monotonic in x).
    UVR_HOST_DEVICE static std::uint32_t cellIndex(const PartitionGrid& g, int a, float x) {
        const float f = (x - g.lo[a]) * g.cellsPerUnit[a];
        if (!(f > 0.f)) return 0;  // also NaN
        const float last = static_cast<float>(g.dims[a] - 1);
        return static_cast<std::uint32_t>(f < last ? f : last);
    }
};

/// Most cells on one axis of a partition's grid.
inline constexpr std::uint32_t kMaxGridSide = 1024;

/// Grid of about `target` cubic-ish cells over box (at least one cell per axis, at most
/// kMaxGridSide; flat boxes get one cell across their flat axis). `first` is left 0.
PartitionGrid layoutPartitionGrid(const Bounds3f& box, double target);

/// One grid per partition of kd (layoutPartitionGrid for about cellCount / tetsPerCell cells;
/// one cell for an empty partition), with `first` set to consecutive offsets; `what` names the
/// grids in the error when their cells exceed 32-bit indices. Shared by the seed and macrocell
/// grids.
std::vector<PartitionGrid> layoutPartitionGrids(const KdPartitions& kd, float tetsPerCell,
                                                const char* what, double tetsPerMeshCell = 1.0);

/// Cells of all grids laid out by layoutPartitionGrids.
inline std::uint64_t gridCellCount(const std::vector<PartitionGrid>& grids) {
    if (grids.empty()) return 0;
    const PartitionGrid& g = grids.back();
    return std::uint64_t(g.first) + std::uint64_t(g.dims[0]) * g.dims[1] * g.dims[2];
}

/// Where a ray leaves grid cell idx of g: the smallest t at which it crosses one of the cell's
/// faces ahead (inv: 1 / the ray's direction). The grid's outer cells reach to infinity outward,
/// as SeedGridView::cellIndex clamps positions outside the grid into them.
UVR_HOST_DEVICE inline float gridCellExit(const PartitionGrid& g, const std::uint32_t idx[3],
                                          Vec3f org, Vec3f inv) {
    float exit = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (!(g.cellsPerUnit[a] > 0.f) || inv[a] == 0.f || !(fabsf(inv[a]) < INFINITY)) continue;
        const bool up = inv[a] > 0.f;
        if (up ? idx[a] + 1 >= g.dims[a] : idx[a] == 0) continue;  // the outer face: unbounded
        const float face =
            g.lo[a] + static_cast<float>(up ? idx[a] + 1 : idx[a]) / g.cellsPerUnit[a];
        const float t = (face - org[a]) * inv[a];
        exit = t < exit ? t : exit;
    }
    return exit;
}

/// Tetrahedra per grid cell the builder aims for: a seed is then about one tetrahedron edge from
/// any point of its cell, so a walk from it takes a few steps whatever the ray's step length.
inline constexpr float kTetsPerSeedCell = 2.f;

/// The bits of a float (for a non-negative one, ordered as the float is).
UVR_HOST_DEVICE inline std::uint32_t floatBits(float f) {
#if defined(__CUDA_ARCH__)
    return __float_as_uint(f);
#else
    return std::bit_cast<std::uint32_t>(f);
#endif
}

/// The seed keys cell t offers grid g (buildSeedGrids' rule): for each grid cell its bounding box
/// overlaps (index i, x fastest) whose best key so far, best(i), exceeds t, offer(i, key) with key
/// = (squared distance from t's centroid to the grid cell's centre, 0 when t contains the centre)
/// << 32 | t. Every key of t is at least t, so a grid cell whose best is no larger (a containing
/// cell of smaller id) is not tested. The seed is the smallest key offered: the CPU's build
/// takes it serially per partition, the GPU's by atomic minima, and both get the same seeds
/// (best(i) may be stale: it only saves tests).
template <class Best, class Offer>
UVR_HOST_DEVICE void offerSeedKeys(const TetLocator& locator, const PartitionGrid& g,
                                   std::uint32_t t, Best&& best, Offer&& offer) {
    Vec3f x[kMaxCellCorners];
    const int corners = locator.mesh.kernelGather(t, x);
    Bounds3f box;
    Vec3f centroid(0.f);
    for (int k = 0; k < corners; ++k) {
        box.extend(x[k]);
        centroid += x[k];
    }
    centroid = centroid * (1.f / float(corners));
    Vec3f cellSize;
    std::uint32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        cellSize[a] = g.cellsPerUnit[a] > 0.f ? 1.f / g.cellsPerUnit[a] : 0.f;
        lo[a] = SeedGridView::cellIndex(g, a, box.lo[a]);
        hi[a] = SeedGridView::cellIndex(g, a, box.hi[a]);
    }
    for (std::uint32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::uint32_t y = lo[1]; y <= hi[1]; ++y)
            for (std::uint32_t xi = lo[0]; xi <= hi[0]; ++xi) {
                const std::uint64_t i = (std::uint64_t(z) * g.dims[1] + y) * g.dims[0] + xi;
                if (best(i) <= t) continue;
                const Vec3f centre(g.lo.x + (xi + 0.5f) * cellSize.x,
                                   g.lo.y + (y + 0.5f) * cellSize.y,
                                   g.lo.z + (z + 0.5f) * cellSize.z);
                float bary[4];
                float dist2 = 0.f;
                if (!locator.inside(t, centre, bary)) {
                    const Vec3f e = centroid - centre;
                    dist2 = dot(e, e);
                }
                // A non-negative float orders as its bits do.
                offer(i, (std::uint64_t(floatBits(dist2)) << 32) | t);
            }
}

/// Seed grids of all partitions: for every grid cell, the partition's tetrahedron containing the
/// cell's centre, else the one overlapping the cell whose centroid lies closest to the centre,
/// else kNoTet. Point location with long steps starts its walk there (O(1) per sample instead of
/// a walk whose length grows with the step, or a BVH search).
struct SeedGrids {
    std::vector<PartitionGrid> grids;
    std::vector<std::uint32_t> seeds;
    double buildSeconds = 0.0;

    /// View for kernels; this object must outlive it.
    SeedGridView view() const { return {grids.data(), seeds.data()}; }
    /// Bytes held (grids and seeds).
    std::uint64_t bytes() const {
        return grids.size() * sizeof(PartitionGrid) + seeds.size() * sizeof(std::uint32_t);
    }
};

/// Builds the seed grids of every partition of kd over mesh, in parallel over partitions; the
/// result does not depend on the thread count. `progress` hears the fraction of cells done.
SeedGrids buildSeedGrids(const TetMesh& mesh, const KdPartitions& kd,
                         float tetsPerCell = kTetsPerSeedCell, const FractionFn& progress = {});

/// Builds seed grids elsewhere (buildSeedGridsCuda: on the GPU): the same grids and seeds as
/// buildSeedGrids.
using SeedBuilder =
    std::function<SeedGrids(const TetMesh&, const KdPartitions&, float, const FractionFn&)>;

}  // namespace uvr

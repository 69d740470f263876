// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>

#include "uvr/accel/bvh.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/host_device.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Most face-to-face steps a walk takes from the previous sample's tetrahedron before the BVH
/// takes over.
inline constexpr int kMaxWalkSteps = 8;

// The points with every barycentric >= -e form the tetrahedron scaled by 1 + 4e about its
// centroid, which reaches at most 3e times the largest extent of the tetrahedron's box beyond it.
static_assert(kBoxPointTolerance >= 3.f * kBaryEpsilon,
              "BVH point queries must hold every point TetLocator::inside accepts");

/// Counters of point-location work for statistics.
struct LocateCounters {
    std::uint64_t walkSteps = 0;   ///< tetrahedra tested while walking
    std::uint64_t bvhQueries = 0;  ///< searches that fell back to the BVH
};

/// Point location in a mesh of tetrahedra and native cells: first the hint (the previous
/// sample's cell), then a walk across faces towards p (ray coherence), then the BVH.
struct TetLocator {
    TetMeshView mesh;
    BvhView bvh;
    /// Face neighbours (compactNeighbors); none present: no walking.
    NeighborView neighbors;
    int maxWalkSteps = kMaxWalkSteps;  ///< walk length before the BVH takes over

    /// True when p lies in cell t (within kBaryEpsilon); fills bary with p's local coordinates
    /// (TetMeshView::interpolate).
    template <bool kNative = true>
    UVR_HOST_DEVICE bool inside(std::uint32_t t, Vec3f p, float bary[4]) const {
        if (kNative && t >= mesh.tetCount) {
            // A cell lies within its corners' box (its map is a convex combination of them):
            // outside it, as the BVH's leaves allow (two cells a leaf on the CPU), p needs no
            // Newton's method (several steps from the centre before it gives up).
            Vec3f x[kMaxCellCorners];
            const int n = mesh.gather(t, x);
            Bounds3f box;
            for (int i = 0; i < n; ++i) box.extend(x[i]);
            if (!boxHoldsPoint(box, p)) return false;
            float excess;
            nativeStepAt(mesh.kind(t), x, p, bary, excess);
            return excess <= kBaryEpsilon;
        }
        BlockVertex x[4];
        mesh.tetVertices(t, x);
        if (!tetBarycentrics(p, x[0].p, x[1].p, x[2].p, x[3].p, bary)) return false;
        return bary[0] >= -kBaryEpsilon && bary[1] >= -kBaryEpsilon && bary[2] >= -kBaryEpsilon &&
               bary[3] >= -kBaryEpsilon;
    }

    /// Native cell t: p's parametric coordinates into bary[0..2] and the face p lies furthest
    /// outside of, with that excess (infinite when Newton's method does not converge: p is then
    /// not in the cell, and the face is the last iterate's).
    /// With fromGuess, Newton's method starts from bary's coordinates (the previous sample's in
    /// this cell) instead of the centre.
    UVR_HOST_DEVICE int nativeStep(std::uint32_t t, Vec3f p, float bary[4], float& excess,
                                   bool fromGuess = false) const {
        Vec3f x[kMaxCellCorners];
        mesh.gather(t, x);
        return nativeStepAt(mesh.kind(t), x, p, bary, excess, fromGuess);
    }

    /// nativeStep of a cell of kind k with corners x (gathered).
    UVR_HOST_DEVICE static int nativeStepAt(CellKind k, const Vec3f* x, Vec3f p, float bary[4],
                                            float& excess, bool fromGuess = false) {
        Vec3f rst(0.f);
        if (fromGuess) {
            // A guess from elsewhere (another kind's coordinates, NaN) starts from the centre.
            rst = Vec3f(bary[0], bary[1], bary[2]);
            fromGuess = rst.x >= -0.5f && rst.x <= 1.5f && rst.y >= -0.5f && rst.y <= 1.5f &&
                        rst.z >= -0.5f && rst.z <= 1.5f;
        }
        const bool converged = cellParametric(k, x, p, rst, fromGuess);
        bary[0] = rst.x, bary[1] = rst.y, bary[2] = rst.z, bary[3] = 0.f;
        const int face = worstFace(k, rst, excess);
        if (!converged) excess = INFINITY;
        return face;
    }

    /// Index of a tetrahedron containing p, or kNoTet; bary receives p's barycentrics in it.
    template <bool kNative = true>
    UVR_HOST_DEVICE std::uint32_t locate(Vec3f p, std::uint32_t hint, float bary[4],
                                         LocateCounters& counters) const {
        return locateIn<kNative>(bvh, 0, p, hint, bary, counters);
    }

    /// As locate, but the BVH fallback searches only the tree at `root` of `tree` (e.g. one
    /// k-d partition's cells).
    template <bool kNative = true>
    UVR_HOST_DEVICE std::uint32_t locateIn(const BvhView& tree, std::uint32_t root, Vec3f p,
                                           std::uint32_t hint, float bary[4],
                                           LocateCounters& counters) const {
        const std::uint32_t t = walk<kNative>(p, hint, bary, counters);
        return t != kNoTet ? t : search<kNative>(tree, root, p, bary, counters);
    }

    /// Walk across faces from tetrahedron `start` towards p (at most maxWalkSteps tetrahedra):
    /// the tetrahedron containing p, or kNoTet when the walk leaves the mesh, meets a degenerate
    /// tetrahedron or runs out of steps (or start is kNoTet, or there are no neighbours).
    template <bool kNative = true>
    UVR_HOST_DEVICE UVR_INLINE std::uint32_t walk(Vec3f p, std::uint32_t start, float bary[4],
                                                  LocateCounters& counters) const {
        if (start == kNoTet || !neighbors.present()) return kNoTet;
        std::uint32_t t = start;
        for (int step = 0; step < maxWalkSteps; ++step) {
            ++counters.walkSteps;
            int worst = 0;
            if (!kNative || t < mesh.tetCount) {
                BlockVertex x[4];
                mesh.tetVertices(t, x);
                if (!tetBarycentrics(p, x[0].p, x[1].p, x[2].p, x[3].p, bary)) return kNoTet;
                for (int i = 1; i < 4; ++i)
                    if (bary[i] < bary[worst]) worst = i;
                if (bary[worst] >= -kBaryEpsilon) return t;
                t = neighbors.ofTet(t, worst);
            } else {
                // A native cell: its parametric coordinates say which face p lies beyond.
                float excess;
                worst = nativeStep(t, p, bary, excess, step == 0);
                if (excess <= kBaryEpsilon) return t;
                t = neighbors.across(mesh, t, worst);
            }
            if (t == kNoTet) return kNoTet;
        }
        return kNoTet;
    }

    /// Search of the tree at `root` of `tree` for a tetrahedron containing p, or kNoTet.
    template <bool kNative = true>
    UVR_HOST_DEVICE std::uint32_t search(const BvhView& tree, std::uint32_t root, Vec3f p,
                                         float bary[4], LocateCounters& counters) const {
        ++counters.bvhQueries;
        std::uint32_t found = kNoTet;
        bvhVisitPoint(
            tree, p,
            [&](std::uint32_t t) {
                if (inside<kNative>(t, p, bary)) {
                    found = t;
                    return true;
                }
                return false;
            },
            root);
        return found;
    }
};

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// A BVH node (32 bytes): a leaf when count > 0 (primitives primIds[first .. first+count)), else
/// an inner node whose children are nodes[first] and nodes[first + 1].
struct BvhNode {
    Bounds3f box;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
};

/// Plain-data view of a BVH for CPU and GPU kernels; node 0 is the root.
struct BvhView {
    const BvhNode* nodes = nullptr;
    /// Leaf entries' primitive ids; null: a leaf's entries [first, first + count) are the ids
    /// themselves (buildCellTree).
    const std::uint32_t* primIds = nullptr;
    std::uint32_t nodeCount = 0;
};

/// Deepest stack a BVH traversal needs; the builders guarantee the tree is no deeper (binned SAH
/// trees stop at 64 levels, linear BVHs need up to 96: lbvh.h).
inline constexpr int kBvhMaxDepth = 96;

/// Relative tolerance of point queries: a box counts as containing points up to this fraction of
/// its largest extent outside it, so a point that a containment test with a relative tolerance
/// accepts (TetLocator::inside) is never lost to rounding at a box face. Child boxes lie inside
/// their parent's and are no larger, so the grown boxes nest as the boxes do.
inline constexpr float kBoxPointTolerance = 4e-5f;

/// True when p lies in b grown by kBoxPointTolerance times b's largest extent.
UVR_HOST_DEVICE UVR_INLINE bool boxHoldsPoint(const Bounds3f& b, Vec3f p) {
    const Vec3f e = b.extent();
    const float m = e.x > e.y ? (e.x > e.z ? e.x : e.z) : (e.y > e.z ? e.y : e.z);
    const float pad = kBoxPointTolerance * m;
    return p.x >= b.lo.x - pad && p.x <= b.hi.x + pad && p.y >= b.lo.y - pad &&
           p.y <= b.hi.y + pad && p.z >= b.lo.z - pad && p.z <= b.hi.z + pad;
}

/// Calls visit(primId) for every primitive whose leaf box holds p (boxHoldsPoint), in the tree
/// rooted at `root`, until visit returns true; returns whether it did.
template <class Visit>
UVR_HOST_DEVICE bool bvhVisitPoint(const BvhView& bvh, Vec3f p, Visit&& visit,
                                   std::uint32_t root = 0) {
    if (bvh.nodeCount == 0) return false;
    std::uint32_t stack[kBvhMaxDepth];
    int top = 0;
    std::uint32_t node = root;
    while (true) {
        const BvhNode& n = bvh.nodes[node];
        if (boxHoldsPoint(n.box, p)) {
            if (n.count > 0) {
                for (std::uint32_t i = 0; i < n.count; ++i)
                    if (visit(bvh.primIds ? bvh.primIds[n.first + i] : n.first + i)) return true;
            } else {
                stack[top++] = n.first + 1;
                node = n.first;
                continue;
            }
        }
        if (top == 0) return false;
        node = stack[--top];
    }
}

/// Build parameters.
struct BvhBuildOptions {
    int maxLeafSize = 4;  ///< primitives per leaf at most (unless they cannot be split)
    int bins = 16;        ///< SAH bins per axis
};

/// A bounding volume hierarchy over boxes, stored as flat arrays.
struct Bvh {
    std::vector<BvhNode> nodes;
    std::vector<std::uint32_t> primIds;

    /// View for kernels; the Bvh must outlive it.
    BvhView view() const {
        return {nodes.data(), primIds.empty() ? nullptr : primIds.data(),
                static_cast<std::uint32_t>(nodes.size())};
    }
};

/// Builds a BVH with binned SAH splits (Wald 2007, "On fast construction of SAH-based bounding
/// volume hierarchies") over primitive boxes and their centres; O(n log n). Depth is bounded by
/// 64 levels (falling back to median splits near the limit). Parallel (large nodes by
/// data-parallel passes, then subtrees one per thread) and bit-identical for any thread count.
Bvh buildBvh(std::span<const Bounds3f> boxes, std::span<const Vec3f> centers,
             const BvhBuildOptions& options = {});

/// Cells per leaf of the cell tree (buildCellTree) for rendering large meshes on a GPU: searches
/// are rare there (walks and seeds locate almost every sample inside the mesh), so large leaves
/// cost little time and keep the tree at 2 bytes per cell. Meshes of up to 2^24 cells keep
/// kCpuCellTreeLeaf's (prepareMesh): there searches are not rare.
inline constexpr std::uint32_t kCellTreeLeaf = 32;

/// Cells per leaf of the cell tree for rendering on the CPU (PrepareOptions::cellTreeLeaf's
/// default): a sample outside a non-convex mesh is searched for, and the search tests every cell
/// of every leaf whose box holds it; with 32-cell leaves, whose boxes overlap, that was 3/4 of
/// the CPU's render time (SPX, 12,936 tetrahedra: 4.2M searches at about 4 us each, against the
/// reference's 0.2 us in its SAH tree). Leaves of 2 cells cost 32 bytes per cell (one 32-byte
/// node per cell) against 2 at 32 (PERFORMANCE.md, "CPU: the cell tree's leaves").
inline constexpr std::uint32_t kCpuCellTreeLeaf = 2;

/// A BVH whose leaves are runs of `leafCells` consecutive cell ids, without primitive ids (a
/// leaf holds cells [first, first + count)): a balanced binary tree over the runs, siblings
/// adjacent. Over cells in Morton order (sortCellsSpatially) the runs are compact. Parallel;
/// `progress` hears the fraction done.
Bvh buildCellTree(const TetMesh& mesh, std::uint32_t leafCells = kCpuCellTreeLeaf,
                  const FractionFn& progress = {});

/// Bounding box and box centre of every cell of a mesh (resizes both arrays); parallel.
void tetBoxesAndCenters(const TetMesh& mesh, std::vector<Bounds3f>& boxes,
                        std::vector<Vec3f>& centers);

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include <bit>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/ray.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// A k-d tree node (8 bytes): an inner node splits `axis` at `split`, its children are
/// nodes[child] (below the plane) and nodes[child + 1] (above); a leaf names partition `child`.
struct KdNode {
    float split = 0.f;
    std::uint32_t bits = 0;  ///< (child << 2) | axis, axis 3 marks a leaf

    UVR_HOST_DEVICE bool isLeaf() const { return (bits & 3u) == 3u; }
    UVR_HOST_DEVICE int axis() const { return static_cast<int>(bits & 3u); }
    UVR_HOST_DEVICE std::uint32_t child() const { return bits >> 2; }
};

/// One partition (Morrical et al. 2019, Sec. 2.1-2.2): a k-d leaf's cells, the leaf region shrunk
/// to the bounds of those cells, and their whole-cell scalar range.
struct KdPartition {
    Bounds3f box;          ///< shrunk: leaf region intersected with the cells' bounds
    float valueMin = 0.f;  ///< finite scalar range over the cells (whole cells)
    float valueMax = 0.f;
    std::uint32_t firstCell = 0;  ///< into KdPartitions::cells
    std::uint32_t cellCount = 0;
};

/// Plain-data view of the partitions for CPU and GPU kernels.
struct KdView {
    const KdNode* nodes = nullptr;
    const KdPartition* partitions = nullptr;
    std::uint32_t partitionCount = 0;
    Bounds3f bounds;  ///< region of the root node
};

/// Deepest k-d tree the builder makes (and the traversal stack holds).
inline constexpr int kKdMaxDepth = 40;

/// Ordered front-to-back traversal of the k-d tree along a ray, one leaf at a time (exact: the
/// interval [tMin, tMax] is cut at each split plane's t, and the pieces come out in order, so no
/// partition is skipped or visited twice whatever the precision). An iterator rather than a
/// callback, so that a GPU thread can interleave "next leaf" with its samples in one loop and
/// the threads of a warp need not wait for each other at every partition boundary.
struct KdLeafIterator {
    struct Entry {
        std::uint32_t node;
        float t0, t1;
    };
    Entry stack[kKdMaxDepth + 1];
    int top = 0;
    std::uint32_t node = 0;
    float t0 = 0.f, t1 = 0.f;
    bool done = false;

    UVR_HOST_DEVICE KdLeafIterator(float tMin, float tMax) : t0(tMin), t1(tMax) {}

    /// The next leaf region the ray crosses: its partition and the consecutive, non-overlapping
    /// piece [a, b) of the ray in it; false once every leaf has been handed out.
    UVR_HOST_DEVICE bool next(const KdView& kd, const Ray& ray, Vec3f invDir, std::uint32_t& leaf,
                              float& a, float& b) {
        if (done) return false;
        while (true) {
            const KdNode n = kd.nodes[node];
            if (!n.isLeaf()) {
                const int axis = n.axis();
                const float o = ray.org[axis], d = ray.dir[axis];
                // Near side: where the ray starts; on the plane, the side it heads to.
                const bool belowFirst = o < n.split || (o == n.split && d <= 0.f);
                const std::uint32_t nearNode = n.child() + (belowFirst ? 0u : 1u);
                const std::uint32_t farNode = n.child() + (belowFirst ? 1u : 0u);
                const float tSplit = (n.split - o) * invDir[axis];
                if (d == 0.f || o == n.split || !(tSplit > 0.f) || tSplit >= t1) {
                    node = nearNode;  // never crossing the plane inside the interval
                } else if (tSplit <= t0) {
                    node = farNode;  // crossed before the interval starts
                } else {
                    stack[top++] = {farNode, tSplit, t1};
                    node = nearNode;
                    t1 = tSplit;
                }
                continue;
            }
            leaf = n.child();
            a = t0;
            b = t1;
            if (top == 0) {
                done = true;
            } else {
                --top;
                node = stack[top].node;
                t0 = stack[top].t0;
                t1 = stack[top].t1;
            }
            return true;
        }
    }
};

/// Calls leaf(partition, t0, t1) for each leaf region the ray crosses in front-to-back order
/// (KdLeafIterator), until leaf returns true (e.g. once the ray is opaque).
template <class Leaf>
UVR_HOST_DEVICE void kdTraverse(const KdView& kd, const Ray& ray, Vec3f invDir, float tMin,
                                float tMax, Leaf&& leaf) {
    KdLeafIterator it(tMin, tMax);
    std::uint32_t p = 0;
    float t0 = 0.f, t1 = 0.f;
    while (it.next(kd, ray, invDir, p, t0, t1))
        if (leaf(p, t0, t1)) return;
}

/// The split rules of the k-d build (Morrical et al. 2019, Sec. 2.1), shared by the CPU build and
/// the GPU's (cuda/kd_build.cu).
namespace kdsplit {

/// Order-preserving map of a float to an unsigned key (radix selection and sorting).
UVR_HOST_DEVICE inline std::uint32_t floatKey(float f) {
#if defined(__CUDA_ARCH__)
    const std::uint32_t u = __float_as_uint(f);
#else
    const std::uint32_t u = std::bit_cast<std::uint32_t>(f);
#endif
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

/// Inverse of floatKey.
UVR_HOST_DEVICE inline float keyFloat(std::uint32_t k) {
    const std::uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
#if defined(__CUDA_ARCH__)
    return __uint_as_float(u);
#else
    return std::bit_cast<float>(u);
#endif
}

/// A node's occupied region: its region clipped to the bounds of its cells.
UVR_HOST_DEVICE inline Bounds3f shrunkRegion(const Bounds3f& region, const Bounds3f& cellBounds) {
    Bounds3f r;
    r.lo = vmax(region.lo, cellBounds.lo);
    r.hi = vmin(region.hi, cellBounds.hi);
    return r;
}

/// Whether a node of `count` cells at `depth` is split at all (else it is a leaf); the split is
/// then along the longest axis of the shrunk region at the median cell centre.
inline bool wantsSplit(std::uint64_t count, int depth, const Bounds3f& shrunk,
                       std::uint32_t leafCells, int maxDepth) {
    return count > leafCells && depth < maxDepth && !shrunk.empty();
}

/// The sides of the plane a cell box goes to: below when it reaches the plane from below, above
/// when it reaches it from above (a cell touching the plane goes to both, so every point of a
/// child's closed region that lies in a cell finds that cell in the child's list).
UVR_HOST_DEVICE inline bool goesBelow(const Bounds3f& box, int axis, float plane) {
    return box.lo[axis] <= plane;
}
UVR_HOST_DEVICE inline bool goesAbove(const Bounds3f& box, int axis, float plane) {
    return box.hi[axis] >= plane;
}

/// Whether a split is kept: the plane strictly inside the region, and neither side left with more
/// than 90% of the cells (which bounds duplication).
inline bool keepsSplit(const Bounds3f& region, int axis, float plane, std::uint64_t below,
                       std::uint64_t above, std::uint64_t count) {
    return plane > region.lo[axis] && plane < region.hi[axis] &&
           (below > above ? below : above) * 10 <= count * 9;
}

}  // namespace kdsplit

/// A k-d tree before its partitions are described: nodes (a leaf names its entry of the leaf
/// arrays), each leaf's shrunk region and its cells (leaf l has cells[begin[l] .. begin[l + 1])).
struct KdTree {
    std::vector<KdNode> nodes;
    std::vector<Bounds3f> leafShrunk;
    std::vector<std::uint64_t> leafBegin{0};
    std::vector<std::uint32_t> leafCells;
};

/// A node of a larger mesh's k-d tree to build a subtree below (a data-parallel rank's piece,
/// dist/): the node's region and depth in that tree, and that mesh's bounds diagonal (the
/// partitions' boxes are padded by a fraction of it).
struct KdSubtreeRoot {
    Bounds3f region;
    int depth = 0;
    float paddingDiagonal = 0.f;
};

struct KdBuildOptions;

/// Builds the k-d tree of buildKdPartitions elsewhere (buildKdTreeCuda: on the GPU).
/// The FractionFn hears how far the build has come.
using KdSplitter = std::function<KdTree(const TetMesh&, const KdBuildOptions&, const FractionFn&)>;

/// Build parameters.
struct KdBuildOptions {
    std::uint32_t leafCells = 1024;  ///< split nodes holding more cells (PERFORMANCE.md)
    int maxDepth = kKdMaxDepth;      ///< never deeper than this (at most kKdMaxDepth)
    /// When set, the k-d tree (splits, leaves and their cells) comes from this splitter
    /// (buildKdTreeCuda: on the GPU; the same partitions as the CPU's); else the CPU threads.
    KdSplitter splitter;
    /// When set, the tree (the splitter's too) is the subtree below this node of a larger mesh's
    /// tree: built from the mesh's cells whose boxes reach the node's closed region (the cells
    /// the larger tree hands that node) by the same rules, so its partitions are that tree's
    /// there when the mesh holds every cell reaching the region. kd.bounds stays the mesh's.
    std::optional<KdSubtreeRoot> root = std::nullopt;
};

/// Spatial k-d partitions of a tetrahedral mesh: convex, disjoint leaf regions, each with its
/// cells (a cell straddling a split goes to both sides), shrunk box and value range. (Samples
/// the walks do not locate search the cell tree, buildCellTree: the partitions keep no BVHs.)
struct KdPartitions {
    std::vector<KdNode> nodes;
    std::vector<KdPartition> partitions;
    std::vector<std::uint32_t> cells;  ///< cell ids of every partition, partition by partition
    Bounds3f bounds;
    std::uint32_t leafCells = 0;  ///< the build's leaf size
    double buildSeconds = 0.0;
    double treeSeconds = 0.0;  ///< of buildSeconds, the k-d tree (the rest: the partitions)

    /// View for kernels; this object must outlive it.
    KdView view() const {
        return {nodes.data(), partitions.data(), static_cast<std::uint32_t>(partitions.size()),
                bounds};
    }
    /// Sum of cells over partitions divided by the mesh's cell count (>= 1).
    double duplicationFactor(std::uint64_t tetCount) const {
        return tetCount ? double(cells.size()) / double(tetCount) : 0.0;
    }
};

/// Builds the partitions with median splits of cell centres along the longest axis of each node
/// (Morrical et al. 2019, Sec. 2.1); O(n log n) for well-shaped meshes. A node whose split would
/// not reduce the larger side below 90% of its cells becomes a leaf, which bounds duplication.
/// Parallel (large nodes by data-parallel passes, then subtrees one per thread) and
/// bit-identical for any thread count. `progress` hears the fraction done.
KdPartitions buildKdPartitions(const TetMesh& mesh, const KdBuildOptions& options = {},
                               const FractionFn& progress = {});

/// Sets every partition's value range: the finite minimum and maximum over its cells' values
/// (whole cells: all four vertices, or the cell's own value for cell data; {0, 0} when none is
/// finite). The only value-dependent part of the partitions: buildKdPartitions ends with it, and
/// new values of the same mesh (a time step) need only this, not a rebuild.
void computePartitionValueRanges(const TetMesh& mesh, KdPartitions& kd);

}  // namespace uvr

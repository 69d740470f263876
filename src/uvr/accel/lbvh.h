// SPDX-License-Identifier: MIT
#pragma once

// Linear BVHs (Karras 2012, "Maximizing parallelism in the construction of BVHs, octrees, and k-d
// trees"): primitives sorted by the Morton code of their box centres and a binary radix tree over
// them, every node computed independently of the others; subtrees of at most `leafSize`
// primitives become leaves, so leaves follow the tree's spatial splits. That is what lets the GPU
// build a BVH over hundreds of millions of tetrahedra in about a second (the CPU's binned SAH takes
// minutes). The per-element math below is shared by the CPU driver (lbvh.cpp, also the GPU's test
// oracle) and the CUDA one (cuda/lbvh_build.cu), so both build bit-identical trees.
//
// Layout (the BvhNode layout of bvh.h): a segment whose radix tree keeps K inner nodes (those of
// more than leafSize primitives) takes 2 K + 1 nodes from its base; the root is node base + 0,
// and the kept inner node of rank r (in index order) has its children at base + 2 r + 1 and
// base + 2 r + 2, so siblings are adjacent. Depth: each level of a radix tree lengthens the common
// prefix of the (63-bit Morton code, 32-bit index) keys by at least a bit, so no path has more
// than 95 inner nodes, within kBvhMaxDepth.

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/morton.h"
#include "uvr/core/runs.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// "No node": the parent of a root.
inline constexpr std::uint32_t kLbvhNone = 0xffffffffu;

UVR_HOST_DEVICE inline int countLeadingZeros64(std::uint64_t x) {
#if defined(__CUDA_ARCH__)
    return __clzll(static_cast<long long>(x));
#else
    return x == 0 ? 64 : __builtin_clzll(x);
#endif
}

/// Karras's delta(i, j): the common prefix length of keys i and j of m sorted keys, ties broken
/// by index (so every key is distinct); -1 when j lies outside [0, m).
UVR_HOST_DEVICE inline int lbvhDelta(const std::uint64_t* keys, std::int64_t m, std::int64_t i,
                                     std::int64_t j) {
    if (j < 0 || j >= m) return -1;
    const std::uint64_t a = keys[i], b = keys[j];
    if (a == b)
        return 32 +
               countLeadingZeros64(static_cast<std::uint64_t>(i) ^ static_cast<std::uint64_t>(j));
    return countLeadingZeros64(a ^ b);
}

/// Inner node i (0 <= i < m - 1) of the radix tree over m sorted keys: the leaves it covers,
/// [first, last], and its split: leaves first..split go left, split + 1..last right. The left
/// child is inner node `split` unless it covers one leaf, the right one inner node split + 1.
struct LbvhInner {
    std::int64_t first = 0, last = 0, split = 0;
};

/// Karras 2012, Fig. 4: the range and split of inner node i.
UVR_HOST_DEVICE inline LbvhInner lbvhInnerNode(const std::uint64_t* keys, std::int64_t m,
                                               std::int64_t i) {
    const int d = lbvhDelta(keys, m, i, i + 1) > lbvhDelta(keys, m, i, i - 1) ? 1 : -1;
    const int deltaMin = lbvhDelta(keys, m, i, i - d);
    std::int64_t lMax = 2;
    while (lbvhDelta(keys, m, i, i + lMax * d) > deltaMin) lMax *= 2;
    std::int64_t l = 0;
    for (std::int64_t t = lMax / 2; t >= 1; t /= 2)
        if (lbvhDelta(keys, m, i, i + (l + t) * d) > deltaMin) l += t;
    const std::int64_t j = i + l * d;
    const int deltaNode = lbvhDelta(keys, m, i, j);
    std::int64_t s = 0, t = l;
    do {
        t = (t + 1) / 2;
        if (lbvhDelta(keys, m, i, i + (s + t) * d) > deltaNode) s += t;
    } while (t > 1);
    LbvhInner r;
    r.first = i < j ? i : j;
    r.last = i < j ? j : i;
    r.split = i + s * d + (d < 0 ? -1 : 0);
    return r;
}

/// The arrays of one build (host vectors for buildLbvhCpu, device memory for buildLbvhCuda), with
/// the per-element work of each step: the drivers only sort, scan, loop or launch over the
/// elements and, for the refit, supply the atomic count and the box loads.
/// Element g of segment s (begin[s] <= g < begin[s + 1]) stands for inner node g - begin[s] of
/// the segment's radix tree.
struct LbvhBuildView {
    TetMeshView mesh;                       ///< points and cells (values unused)
    const std::uint32_t* tetIds = nullptr;  ///< null: primitive i is cell i
    const std::uint64_t* segmentBegin = nullptr;
    const Bounds3f* segmentBounds = nullptr;  ///< what each segment's Morton codes quantise
    std::uint32_t segments = 0;
    std::int64_t leafSize = 1;
    const std::uint64_t* keys = nullptr;            ///< sorted Morton keys, per element
    const std::uint32_t* order = nullptr;           ///< input position of each sorted element
    const std::uint32_t* rank = nullptr;            ///< n + 1: kept inner nodes before element g
    const std::uint32_t* occupiedBefore = nullptr;  ///< LbvhPlan::occupiedBefore
    std::uint32_t* roots = nullptr;
    std::uint32_t* innerSlot = nullptr;
    std::uint32_t* innerParent = nullptr;
    BvhNode* nodes = nullptr;

    UVR_HOST_DEVICE std::uint32_t segmentOf(std::uint64_t g) const {
        return runOf(segmentBegin, segments, g);
    }
    UVR_HOST_DEVICE Bounds3f primBounds(std::uint64_t prim) const {
        return mesh.cellBounds(tetIds ? tetIds[prim] : prim);
    }
    /// Step 1: the Morton key of primitive `prim` (input position) of segment s.
    UVR_HOST_DEVICE std::uint64_t mortonKey(std::uint64_t prim, std::uint32_t s) const {
        return morton63(primBounds(prim).center(), segmentBounds[s]);
    }
    /// A leaf over sorted elements [first, first + count).
    UVR_HOST_DEVICE BvhNode leaf(std::uint64_t first, std::uint64_t count) const {
        BvhNode node;
        for (std::uint64_t k = first; k < first + count; ++k) node.box.extend(primBounds(order[k]));
        node.first = static_cast<std::uint32_t>(first);
        node.count = static_cast<std::uint32_t>(count);
        return node;
    }
    UVR_HOST_DEVICE LbvhInner inner(std::int64_t g, std::uint32_t s) const {
        const std::int64_t b = static_cast<std::int64_t>(segmentBegin[s]);
        return lbvhInnerNode(keys + b, static_cast<std::int64_t>(segmentBegin[s + 1]) - b, g - b);
    }
    /// Step 2: whether element g is an inner node of more than leafSize primitives (kept).
    UVR_HOST_DEVICE bool keepsInner(std::int64_t g) const {
        const std::uint32_t s = segmentOf(g);
        if (g + 1 >= static_cast<std::int64_t>(segmentBegin[s + 1])) return false;  // no node
        const LbvhInner r = inner(g, s);
        return r.last - r.first + 1 > leafSize;
    }
    UVR_HOST_DEVICE bool kept(std::int64_t g) const { return rank[g + 1] != rank[g]; }
    /// The first of kept inner node g's two adjacent child nodes.
    UVR_HOST_DEVICE std::uint32_t firstChild(std::uint32_t s, std::int64_t g) const {
        return roots[s] + 2 * (rank[g] - rank[segmentBegin[s]]) + 1;
    }
    /// Segment s's root node (once rank is known); a segment of at most leafSize primitives is
    /// that one leaf, written here.
    UVR_HOST_DEVICE void placeRoot(std::uint32_t s) const {
        const std::uint64_t b = segmentBegin[s], count = segmentBegin[s + 1] - b;
        roots[s] = 2 * rank[b] + occupiedBefore[s];
        if (count > 0 && count <= static_cast<std::uint64_t>(leafSize))
            nodes[roots[s]] = leaf(b, count);
    }
    /// Step 3, for kept inner node g: its kept children learn their node and parent, its leaf
    /// children are written.
    UVR_HOST_DEVICE void nameChildren(std::int64_t g) const {
        const std::uint32_t s = segmentOf(g);
        const std::int64_t b = static_cast<std::int64_t>(segmentBegin[s]);
        const LbvhInner r = inner(g, s);
        const std::uint32_t slot = firstChild(s, g);
        if (g == b) innerSlot[g] = roots[s], innerParent[g] = kLbvhNone;
        const std::int64_t lo[2] = {r.first, r.split + 1}, hi[2] = {r.split, r.last};
        for (int side = 0; side < 2; ++side) {
            const std::int64_t count = hi[side] - lo[side] + 1;
            if (count > leafSize) {
                const std::int64_t child = b + r.split + side;
                innerSlot[child] = slot + side;
                innerParent[child] = static_cast<std::uint32_t>(g);
            } else {
                nodes[slot + side] = leaf(b + lo[side], count);
            }
        }
    }
    /// Step 4, for kept inner node g: once per leaf child, up the tree; at each node,
    /// firstArrival(p) counts the arrival and says whether it was the first (then the sibling's
    /// subtree is not done and its last thread goes on), loadBox reads a child's box as another
    /// thread wrote it.
    template <class FirstArrival, class LoadBox>
    UVR_HOST_DEVICE void refitFrom(std::int64_t g, FirstArrival&& firstArrival,
                                   LoadBox&& loadBox) const {
        const std::uint32_t s = segmentOf(g);
        const LbvhInner r = inner(g, s);
        const int leafChildren =
            (r.split - r.first + 1 <= leafSize) + (r.last - r.split <= leafSize);
        for (int k = 0; k < leafChildren; ++k) {
            for (std::uint32_t p = static_cast<std::uint32_t>(g); p != kLbvhNone;
                 p = innerParent[p]) {
                if (firstArrival(p)) break;
                const std::uint32_t left = firstChild(s, p);
                BvhNode node;
                node.box = loadBox(nodes + left);
                node.box.extend(loadBox(nodes + left + 1));
                node.first = left;
                node.count = 0;
                nodes[innerSlot[p]] = node;
            }
        }
    }
};

/// What an LBVH build reads: primitives are tetrahedra (tetIds[i], or i when tetIds is empty),
/// grouped in consecutive segments that each get their own tree (one segment for the mesh BVH).
struct LbvhInput {
    const TetMesh* mesh = nullptr;
    std::span<const std::uint32_t> tetIds;    ///< primitive -> tetrahedron; empty: the identity
    std::vector<std::uint64_t> segmentBegin;  ///< S + 1 offsets into the primitives
    std::vector<Bounds3f> segmentBounds;      ///< S boxes the Morton codes quantise
    int leafSize = 4;                         ///< primitives per leaf at most

    std::uint64_t primCount() const {
        return tetIds.empty() ? (mesh ? mesh->cellCount() : 0) : tetIds.size();
    }
};

/// Per segment, how many before it hold primitives (each adds a root or single leaf to the
/// node count: 2 K + 1 per segment).
struct LbvhPlan {
    std::vector<std::uint32_t> occupiedBefore;  ///< S + 1 entries
};

/// Checks the input (offsets, sizes, 32-bit limits; throws Error(Internal) naming what is wrong)
/// and counts the occupied segments.
LbvhPlan planLbvh(const LbvhInput& input);

/// A built LBVH: the nodes of every segment, the primitives in leaf order (order[k] is the input
/// position of the k-th; leaves name ranges of k), and each segment's root node (its base; an
/// empty segment has no nodes).
struct LbvhResult {
    std::vector<BvhNode> nodes;
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> roots;
};

/// An LBVH builder: the CPU one (buildLbvhCpu) or the CUDA one (buildLbvhCuda).
using LbvhBuilder = std::function<LbvhResult(const LbvhInput&)>;

/// Builds the LBVHs on the CPU threads (OpenMP); the GPU's builder returns the same trees.
LbvhResult buildLbvhCpu(const LbvhInput& input);

/// The mesh BVH over every tetrahedron, built by an LBVH builder.
Bvh buildMeshLbvh(const TetMesh& mesh, const LbvhBuilder& build, int leafSize = 4);

}  // namespace uvr

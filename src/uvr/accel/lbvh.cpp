// SPDX-License-Identifier: MIT
#include "uvr/accel/lbvh.h"

#include <algorithm>
#include <atomic>
#include <utility>

#include "uvr/core/error.h"

namespace uvr {

LbvhPlan planLbvh(const LbvhInput& input) {
    UVR_CHECK(input.mesh != nullptr, "LBVH input without a mesh");
    UVR_CHECK(input.leafSize >= 1, "LBVH leaf size must be positive");
    const std::size_t segments = input.segmentBounds.size();
    UVR_CHECK(input.segmentBegin.size() == segments + 1 && input.segmentBegin.front() == 0 &&
                  input.segmentBegin.back() == input.primCount(),
              "LBVH segment offsets do not cover the primitives");
    // 2 n nodes at most (n primitives, leaves of one): 32-bit node indices.
    UVR_CHECK(input.primCount() < 0x7fffffffull, "too many primitives for a 32-bit BVH");
    LbvhPlan plan;
    plan.occupiedBefore.assign(segments + 1, 0);
    for (std::size_t s = 0; s < segments; ++s) {
        UVR_CHECK(input.segmentBegin[s + 1] >= input.segmentBegin[s],
                  "LBVH segment offsets must ascend");
        plan.occupiedBefore[s + 1] =
            plan.occupiedBefore[s] + (input.segmentBegin[s + 1] > input.segmentBegin[s]);
    }
    return plan;
}

LbvhResult buildLbvhCpu(const LbvhInput& input) {
    const LbvhPlan plan = planLbvh(input);
    const std::int64_t n = static_cast<std::int64_t>(input.primCount());
    const std::int64_t segments = static_cast<std::int64_t>(input.segmentBounds.size());
    const Vec3f* points = input.mesh->points.data();
    const Tet* tets = input.mesh->tets.data();
    const std::uint32_t* tetIds = input.tetIds.empty() ? nullptr : input.tetIds.data();
    const std::uint64_t* begin = input.segmentBegin.data();
    const std::uint32_t segCount = static_cast<std::uint32_t>(segments);
    const std::int64_t leaf = input.leafSize;
    LbvhResult out;
    out.order.resize(n);
    out.roots.resize(segments);
    // Step 1: Morton keys, sorted by (key, position) within each segment.
    std::vector<std::uint64_t> keys(n);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t s = 0; s < segments; ++s) {
        const std::int64_t b = static_cast<std::int64_t>(begin[s]);
        const std::int64_t e = static_cast<std::int64_t>(begin[s + 1]);
        std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(e - b);
        for (std::int64_t i = b; i < e; ++i) {
            const std::uint32_t t = tetIds ? tetIds[i] : static_cast<std::uint32_t>(i);
            pairs[i - b] = {morton63(tetBounds(points, tets[t]).center(), input.segmentBounds[s]),
                            static_cast<std::uint32_t>(i)};
        }
        std::sort(pairs.begin(), pairs.end());
        for (std::int64_t i = b; i < e; ++i) {
            keys[i] = pairs[i - b].first;
            out.order[i] = pairs[i - b].second;
        }
    }
    // Inner node i of segment s is element begin[s] + i of the per-element arrays.
    auto innerOf = [&](std::int64_t g, std::uint32_t s) {
        const std::int64_t b = static_cast<std::int64_t>(begin[s]);
        return lbvhInnerNode(keys.data() + b, static_cast<std::int64_t>(begin[s + 1]) - b, g - b);
    };
    // Step 2: which inner nodes are kept (more than `leaf` primitives), their ranks and the
    // segments' node bases.
    std::vector<std::uint32_t> rank(n + 1, 0u);
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g) {
        const std::uint32_t s = lbvhSegmentOf(begin, segCount, g);
        if (g + 1 >= static_cast<std::int64_t>(begin[s + 1])) continue;  // the last has none
        const LbvhInner r = innerOf(g, s);
        rank[g + 1] = r.last - r.first + 1 > leaf;
    }
    for (std::int64_t g = 0; g < n; ++g) rank[g + 1] += rank[g];  // exclusive scan
    for (std::int64_t s = 0; s < segments; ++s)
        out.roots[s] = 2 * rank[begin[s]] + plan.occupiedBefore[s];
    out.nodes.resize(2 * std::uint64_t(rank[n]) + plan.occupiedBefore[segments]);
    // Step 3: kept inner nodes name their children: slots and parents of kept ones, the leaves
    // written at once. A segment of at most `leaf` primitives is one leaf.
    std::vector<std::uint32_t> innerSlot(n), innerParent(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t s = 0; s < segments; ++s) {
        const std::uint64_t count = begin[s + 1] - begin[s];
        if (count > 0 && count <= static_cast<std::uint64_t>(leaf))
            out.nodes[out.roots[s]] =
                lbvhLeaf(points, tets, tetIds, out.order.data(), begin[s], count);
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g) {
        if (rank[g + 1] == rank[g]) continue;  // not kept
        const std::uint32_t s = lbvhSegmentOf(begin, segCount, g);
        const std::int64_t b = static_cast<std::int64_t>(begin[s]);
        const LbvhInner r = innerOf(g, s);
        const std::uint32_t slot = out.roots[s] + 2 * (rank[g] - rank[b]) + 1;
        if (g == b) innerSlot[g] = out.roots[s], innerParent[g] = kLbvhNone;
        const std::int64_t lo[2] = {r.first, r.split + 1}, hi[2] = {r.split, r.last};
        for (int side = 0; side < 2; ++side) {
            const std::int64_t count = hi[side] - lo[side] + 1;
            if (count > leaf) {
                const std::int64_t child = b + r.split + side;
                innerSlot[child] = slot + side;
                innerParent[child] = static_cast<std::uint32_t>(g);
            } else {
                out.nodes[slot + side] =
                    lbvhLeaf(points, tets, tetIds, out.order.data(), b + lo[side], count);
            }
        }
    }
    // Step 4: from each leaf up: the second child to arrive at a node computes its box.
    std::vector<std::uint32_t> arrived(n, 0u);
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g) {
        if (rank[g + 1] == rank[g]) continue;
        const std::uint32_t s = lbvhSegmentOf(begin, segCount, g);
        const std::int64_t b = static_cast<std::int64_t>(begin[s]);
        const LbvhInner r = innerOf(g, s);
        const int leafChildren = (r.split - r.first + 1 <= leaf) + (r.last - r.split <= leaf);
        for (int k = 0; k < leafChildren; ++k) {
            for (std::uint32_t p = static_cast<std::uint32_t>(g); p != kLbvhNone;
                 p = innerParent[p]) {
                if (std::atomic_ref<std::uint32_t>(arrived[p]).fetch_add(
                        1, std::memory_order_acq_rel) == 0)
                    break;  // the sibling's subtree is not done yet: its last thread goes on
                const std::uint32_t left = out.roots[s] + 2 * (rank[p] - rank[b]) + 1;
                Bounds3f box = out.nodes[left].box;
                box.extend(out.nodes[left + 1].box);
                out.nodes[innerSlot[p]] = {box, left, 0};
            }
        }
    }
    return out;
}

Bvh buildMeshLbvh(const TetMesh& mesh, const LbvhBuilder& build, int leafSize) {
    LbvhInput input;
    input.mesh = &mesh;
    input.segmentBegin = {0, mesh.tets.size()};
    input.segmentBounds = {mesh.bounds};
    input.leafSize = leafSize;
    LbvhResult r = build(input);
    Bvh bvh;
    bvh.nodes = std::move(r.nodes);
    bvh.primIds = std::move(r.order);  // input positions are tetrahedron ids
    return bvh;
}

}  // namespace uvr

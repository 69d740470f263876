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
    LbvhResult out;
    out.order.resize(n);
    out.roots.resize(segments);
    std::vector<std::uint64_t> keys(n);
    std::vector<std::uint32_t> rank(n + 1, 0u), innerSlot(n), innerParent(n), arrived(n, 0u);
    LbvhBuildView v;
    v.mesh = input.mesh->view();
    v.tetIds = input.tetIds.empty() ? nullptr : input.tetIds.data();
    v.segmentBegin = input.segmentBegin.data();
    v.segmentBounds = input.segmentBounds.data();
    v.segments = static_cast<std::uint32_t>(segments);
    v.leafSize = input.leafSize;
    v.keys = keys.data();
    v.order = out.order.data();
    v.rank = rank.data();
    v.occupiedBefore = plan.occupiedBefore.data();
    v.roots = out.roots.data();
    v.innerSlot = innerSlot.data();
    v.innerParent = innerParent.data();
    // Step 1: Morton keys, sorted by (key, position) within each segment.
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t s = 0; s < segments; ++s) {
        const std::int64_t b = static_cast<std::int64_t>(input.segmentBegin[s]);
        const std::int64_t e = static_cast<std::int64_t>(input.segmentBegin[s + 1]);
        std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs(e - b);
        for (std::int64_t i = b; i < e; ++i)
            pairs[i - b] = {v.mortonKey(i, static_cast<std::uint32_t>(s)),
                            static_cast<std::uint32_t>(i)};
        std::sort(pairs.begin(), pairs.end());
        for (std::int64_t i = b; i < e; ++i) {
            keys[i] = pairs[i - b].first;
            out.order[i] = pairs[i - b].second;
        }
    }
    // Steps 2-4 (LbvhBuildView): kept inner nodes, their ranks (an exclusive scan) and the
    // roots; children; the refit.
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g) rank[g + 1] = v.keepsInner(g);
    for (std::int64_t g = 0; g < n; ++g) rank[g + 1] += rank[g];
    out.nodes.resize(2 * std::uint64_t(rank[n]) + plan.occupiedBefore[segments]);
    v.nodes = out.nodes.data();
    for (std::int64_t s = 0; s < segments; ++s) v.placeRoot(static_cast<std::uint32_t>(s));
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g)
        if (v.kept(g)) v.nameChildren(g);
    auto firstArrival = [&](std::uint32_t p) {
        return std::atomic_ref<std::uint32_t>(arrived[p]).fetch_add(1, std::memory_order_acq_rel) ==
               0;
    };
    auto loadBox = [](const BvhNode* node) { return node->box; };
#pragma omp parallel for schedule(static)
    for (std::int64_t g = 0; g < n; ++g)
        if (v.kept(g)) v.refitFrom(g, firstArrival, loadBox);
    return out;
}

Bvh buildMeshLbvh(const TetMesh& mesh, const LbvhBuilder& build, int leafSize) {
    LbvhInput input;
    input.mesh = &mesh;
    input.segmentBegin = {0, mesh.cellCount()};
    input.segmentBounds = {mesh.bounds};
    input.leafSize = leafSize;
    LbvhResult r = build(input);
    Bvh bvh;
    bvh.nodes = std::move(r.nodes);
    bvh.primIds = std::move(r.order);  // input positions are tetrahedron ids
    return bvh;
}

}  // namespace uvr

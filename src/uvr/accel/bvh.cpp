// SPDX-License-Identifier: MIT
#include "uvr/accel/bvh.h"

#include <algorithm>
#include <numeric>

#include "uvr/core/error.h"

namespace uvr {

namespace {

float halfArea(const Bounds3f& b) {
    if (b.empty()) return 0.f;
    const Vec3f e = b.extent();
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

struct Task {
    std::uint32_t node, begin, end, depth;
};

}  // namespace

Bvh buildBvh(std::span<const Bounds3f> boxes, std::span<const Vec3f> centers,
             const BvhBuildOptions& options) {
    UVR_CHECK(boxes.size() == centers.size(), "boxes and centres differ in count");
    UVR_CHECK(boxes.size() < 0xffffffffull, "too many primitives for a 32-bit BVH");
    Bvh bvh;
    const std::uint32_t n = static_cast<std::uint32_t>(boxes.size());
    if (n == 0) return bvh;
    bvh.primIds.resize(n);
    std::iota(bvh.primIds.begin(), bvh.primIds.end(), 0u);
    bvh.nodes.reserve(2 * (n / std::max(1, options.maxLeafSize)) + 2);
    bvh.nodes.emplace_back();
    std::vector<Task> stack{{0, 0, n, 1}};
    const int nb = std::max(2, options.bins);
    std::vector<Bounds3f> binBox(nb), rightBox(nb);
    std::vector<std::uint32_t> binCount(nb), rightCount(nb);
    std::uint32_t* ids = bvh.primIds.data();
    while (!stack.empty()) {
        const Task t = stack.back();
        stack.pop_back();
        Bounds3f box, cbox;
        for (std::uint32_t i = t.begin; i < t.end; ++i) {
            box.extend(boxes[ids[i]]);
            cbox.extend(centers[ids[i]]);
        }
        bvh.nodes[t.node].box = box;
        const std::uint32_t count = t.end - t.begin;
        auto makeLeaf = [&] {
            bvh.nodes[t.node].first = t.begin;
            bvh.nodes[t.node].count = count;
        };
        if (count <= static_cast<std::uint32_t>(options.maxLeafSize)) {
            makeLeaf();
            continue;
        }
        // Binned SAH over the three axes of the centre bounds.
        int bestAxis = -1, bestSplit = 0;
        float bestCost = INFINITY;
        const Vec3f cext = cbox.extent();
        if (t.depth + 2 < kBvhMaxDepth) {
            // Large nodes bin only the longest centre axis (a third of the work, nearly the
            // same trees); small nodes try all three.
            const bool allAxes = count <= 4096;
            for (int axis = 0; axis < 3; ++axis) {
                if (!(cext[axis] > 0.f) || (!allAxes && axis != cbox.longestAxis())) continue;
                const float scale = nb / cext[axis];
                std::fill(binBox.begin(), binBox.end(), Bounds3f{});
                std::fill(binCount.begin(), binCount.end(), 0u);
                for (std::uint32_t i = t.begin; i < t.end; ++i) {
                    int b = static_cast<int>((centers[ids[i]][axis] - cbox.lo[axis]) * scale);
                    b = std::clamp(b, 0, nb - 1);
                    binBox[b].extend(boxes[ids[i]]);
                    ++binCount[b];
                }
                Bounds3f acc;
                std::uint32_t accCount = 0;
                for (int b = nb - 1; b > 0; --b) {
                    acc.extend(binBox[b]);
                    accCount += binCount[b];
                    rightBox[b] = acc;
                    rightCount[b] = accCount;
                }
                acc = Bounds3f{};
                accCount = 0;
                for (int b = 0; b < nb - 1; ++b) {
                    acc.extend(binBox[b]);
                    accCount += binCount[b];
                    if (accCount == 0 || rightCount[b + 1] == 0) continue;
                    const float cost =
                        halfArea(acc) * accCount + halfArea(rightBox[b + 1]) * rightCount[b + 1];
                    if (cost < bestCost) {
                        bestCost = cost;
                        bestAxis = axis;
                        bestSplit = b + 1;
                    }
                }
            }
        }
        std::uint32_t mid;
        if (bestAxis >= 0) {
            const float scale = nb / cext[bestAxis];
            const float lo = cbox.lo[bestAxis];
            mid = static_cast<std::uint32_t>(
                std::partition(ids + t.begin, ids + t.end,
                               [&](std::uint32_t id) {
                                   int b = static_cast<int>((centers[id][bestAxis] - lo) * scale);
                                   return std::clamp(b, 0, nb - 1) < bestSplit;
                               }) -
                ids);
        } else {
            // All centres coincide (or the depth limit is near): split by count.
            if (t.depth + 1 >= kBvhMaxDepth) {
                makeLeaf();
                continue;
            }
            const int axis = cbox.longestAxis();
            mid = t.begin + count / 2;
            std::nth_element(ids + t.begin, ids + mid, ids + t.end,
                             [&](std::uint32_t a, std::uint32_t b) {
                                 return centers[a][axis] < centers[b][axis];
                             });
        }
        const std::uint32_t left = static_cast<std::uint32_t>(bvh.nodes.size());
        bvh.nodes[t.node].first = left;
        bvh.nodes[t.node].count = 0;
        bvh.nodes.emplace_back();
        bvh.nodes.emplace_back();
        stack.push_back({left + 1, mid, t.end, t.depth + 1});
        stack.push_back({left, t.begin, mid, t.depth + 1});
    }
    return bvh;
}

}  // namespace uvr

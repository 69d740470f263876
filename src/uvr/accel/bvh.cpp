// SPDX-License-Identifier: MIT
#include "uvr/accel/bvh.h"

#include <algorithm>
#include <numeric>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"

namespace uvr {

namespace {

/// Deepest SAH tree (within kBvhMaxDepth).
constexpr int kSahMaxDepth = 64;
static_assert(kSahMaxDepth <= kBvhMaxDepth);

float halfArea(const Bounds3f& b) {
    if (b.empty()) return 0.f;
    const Vec3f e = b.extent();
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

struct Task {
    std::uint32_t node, begin, end, depth;
};

/// Bin of centre coordinate v among nb bins of width 1 / scale from lo, clamped to [0, nb - 1]
/// before converting (NaN to 0): a centre extent so small (denormal) that nb / extent overflows to
/// infinity still bins every centre, above lo into the last bin and at lo into the first.
int binIndex(float v, float lo, float scale, int nb) {
    const float f = (v - lo) * scale;
    return f > 0.f ? (f < float(nb - 1) ? static_cast<int>(f) : nb - 1) : 0;
}

/// Nodes with more primitives are split by data-parallel passes; smaller ones are whole subtrees
/// built by one thread each. Fixed (not derived from the thread count), so the tree is the same
/// whatever the number of threads.
constexpr std::uint32_t kSubtreePrims = 1u << 17;
/// Primitives per chunk of a data-parallel pass: at least 32 chunks per large node, so many cores
/// share even the smallest of them (the results do not depend on the chunk size).
constexpr std::int64_t kChunk = 1 << 12;

/// The SAH sweep over binned boxes and counts: the best split bin on this axis, if it beats
/// bestCost (then bestCost, bestAxis and bestSplit are updated).
void sweepBins(int axis, int nb, const Bounds3f* binBox, const std::uint32_t* binCount,
               Bounds3f* rightBox, std::uint32_t* rightCount, float& bestCost, int& bestAxis,
               int& bestSplit) {
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
        const float cost = halfArea(acc) * accCount + halfArea(rightBox[b + 1]) * rightCount[b + 1];
        if (cost < bestCost) {
            bestCost = cost;
            bestAxis = axis;
            bestSplit = b + 1;
        }
    }
}

/// A primitive's box, centre and id, gathered so that a subtree's passes read memory in order.
struct Prim {
    Bounds3f box;
    Vec3f center;
    std::uint32_t id;
};

/// Builds the subtree of root task `root` into `nodes` (nodes[0] is its root, inner nodes name
/// local child indices, leaves global ranges of ids); one thread. The primitives are copied into
/// a local array that is partitioned in place (cache-friendly), then their ids written back.
void buildSubtree(std::span<const Bounds3f> boxes, std::span<const Vec3f> centers,
                  std::uint32_t* ids, Task root, const BvhBuildOptions& options,
                  std::vector<BvhNode>& nodes) {
    const std::uint32_t offset = root.begin;
    std::vector<Prim> prims(root.end - root.begin);
    for (std::uint32_t i = 0; i < prims.size(); ++i) {
        const std::uint32_t id = ids[offset + i];
        prims[i] = {boxes[id], centers[id], id};
    }
    Prim* p = prims.data();
    nodes.clear();
    nodes.emplace_back();
    std::vector<Task> stack{{0, 0, root.end - offset, root.depth}};
    const int nb = std::max(2, options.bins);
    std::vector<Bounds3f> binBox(nb), rightBox(nb);
    std::vector<std::uint32_t> binCount(nb), rightCount(nb);
    while (!stack.empty()) {
        const Task t = stack.back();
        stack.pop_back();
        Bounds3f box, cbox;
        for (std::uint32_t i = t.begin; i < t.end; ++i) {
            box.extend(p[i].box);
            cbox.extend(p[i].center);
        }
        nodes[t.node].box = box;
        const std::uint32_t count = t.end - t.begin;
        auto makeLeaf = [&] {
            nodes[t.node].first = offset + t.begin;
            nodes[t.node].count = count;
        };
        if (count <= static_cast<std::uint32_t>(options.maxLeafSize)) {
            makeLeaf();
            continue;
        }
        // Binned SAH over the three axes of the centre bounds.
        int bestAxis = -1, bestSplit = 0;
        float bestCost = INFINITY;
        const Vec3f cext = cbox.extent();
        if (t.depth + 2 < kSahMaxDepth) {
            // Large nodes bin only the longest centre axis (a third of the work, nearly the
            // same trees); small nodes try all three.
            const bool allAxes = count <= 4096;
            for (int axis = 0; axis < 3; ++axis) {
                if (!(cext[axis] > 0.f) || (!allAxes && axis != cbox.longestAxis())) continue;
                const float scale = nb / cext[axis];
                std::fill(binBox.begin(), binBox.end(), Bounds3f{});
                std::fill(binCount.begin(), binCount.end(), 0u);
                for (std::uint32_t i = t.begin; i < t.end; ++i) {
                    const int b = binIndex(p[i].center[axis], cbox.lo[axis], scale, nb);
                    binBox[b].extend(p[i].box);
                    ++binCount[b];
                }
                sweepBins(axis, nb, binBox.data(), binCount.data(), rightBox.data(),
                          rightCount.data(), bestCost, bestAxis, bestSplit);
            }
        }
        std::uint32_t mid;
        if (bestAxis >= 0) {
            const float scale = nb / cext[bestAxis];
            const float lo = cbox.lo[bestAxis];
            mid = static_cast<std::uint32_t>(
                std::partition(p + t.begin, p + t.end,
                               [&](const Prim& q) {
                                   return binIndex(q.center[bestAxis], lo, scale, nb) < bestSplit;
                               }) -
                p);
        } else {
            // All centres coincide (or the depth limit is near): split by count.
            if (t.depth + 1 >= kSahMaxDepth) {
                makeLeaf();
                continue;
            }
            const int axis = cbox.longestAxis();
            mid = t.begin + count / 2;
            std::nth_element(p + t.begin, p + mid, p + t.end, [&](const Prim& a, const Prim& b) {
                return a.center[axis] < b.center[axis];
            });
        }
        const std::uint32_t left = static_cast<std::uint32_t>(nodes.size());
        nodes[t.node].first = left;
        nodes[t.node].count = 0;
        nodes.emplace_back();
        nodes.emplace_back();
        stack.push_back({left + 1, mid, t.end, t.depth + 1});
        stack.push_back({left, t.begin, mid, t.depth + 1});
    }
    for (std::uint32_t i = 0; i < prims.size(); ++i) ids[offset + i] = prims[i].id;
}

/// Splits a large node with data-parallel passes (bounds, binned SAH on the longest centre axis,
/// stable partition through `scratch`); returns the split position, or t.end when the node should
/// be left to buildSubtree (coincident centres, depth limit). Sets nodes[t.node].box.
std::uint32_t splitLarge(std::span<const Bounds3f> boxes, std::span<const Vec3f> centers,
                         std::uint32_t* ids, std::uint32_t* scratch, const Task& t,
                         const BvhBuildOptions& options, Bounds3f& nodeBox) {
    const std::int64_t count = t.end - t.begin;
    const std::int64_t chunks = (count + kChunk - 1) / kChunk;
    auto chunkRange = [&](std::int64_t c) {
        const std::uint32_t b = t.begin + static_cast<std::uint32_t>(c * kChunk);
        return std::pair{b, static_cast<std::uint32_t>(std::min<std::int64_t>(t.end, b + kChunk))};
    };
    // Bounds of boxes and centres (min/max: exact in any order).
    std::vector<Bounds3f> chunkBox(chunks), chunkCenters(chunks);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [b, e] = chunkRange(c);
        for (std::uint32_t i = b; i < e; ++i) {
            chunkBox[c].extend(boxes[ids[i]]);
            chunkCenters[c].extend(centers[ids[i]]);
        }
    }
    Bounds3f box, cbox;
    for (std::int64_t c = 0; c < chunks; ++c) box.extend(chunkBox[c]), cbox.extend(chunkCenters[c]);
    nodeBox = box;
    const int axis = cbox.longestAxis();
    const float ext = cbox.extent()[axis];
    if (t.depth + 2 >= kSahMaxDepth || !(ext > 0.f)) return t.end;
    // Binned SAH on the longest centre axis, as buildSubtree does for large nodes.
    const int nb = std::max(2, options.bins);
    const float scale = nb / ext, lo = cbox.lo[axis];
    auto binOf = [&](std::uint32_t id) { return binIndex(centers[id][axis], lo, scale, nb); };
    std::vector<Bounds3f> chunkBins(chunks * nb);
    std::vector<std::uint32_t> chunkCounts(chunks * nb, 0u);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [b, e] = chunkRange(c);
        for (std::uint32_t i = b; i < e; ++i) {
            const int bin = binOf(ids[i]);
            chunkBins[c * nb + bin].extend(boxes[ids[i]]);
            ++chunkCounts[c * nb + bin];
        }
    }
    std::vector<Bounds3f> binBox(nb), rightBox(nb);
    std::vector<std::uint32_t> binCount(nb, 0u), rightCount(nb);
    for (std::int64_t c = 0; c < chunks; ++c)
        for (int b = 0; b < nb; ++b) {
            binBox[b].extend(chunkBins[c * nb + b]);
            binCount[b] += chunkCounts[c * nb + b];
        }
    float bestCost = INFINITY;
    int bestAxis = -1, bestSplit = 0;
    sweepBins(axis, nb, binBox.data(), binCount.data(), rightBox.data(), rightCount.data(),
              bestCost, bestAxis, bestSplit);
    if (bestAxis < 0) return t.end;
    // Stable parallel partition: left counts per chunk, their prefix sums, scatter, copy back.
    std::vector<std::uint32_t> leftBefore(chunks + 1, 0u);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [b, e] = chunkRange(c);
        std::uint32_t left = 0;
        for (std::uint32_t i = b; i < e; ++i) left += binOf(ids[i]) < bestSplit;
        leftBefore[c + 1] = left;
    }
    for (std::int64_t c = 0; c < chunks; ++c) leftBefore[c + 1] += leftBefore[c];
    const std::uint32_t totalLeft = leftBefore[chunks];
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const auto [b, e] = chunkRange(c);
        std::uint32_t l = t.begin + leftBefore[c];
        std::uint32_t r = t.begin + totalLeft + (b - t.begin - leftBefore[c]);
        for (std::uint32_t i = b; i < e; ++i) {
            if (binOf(ids[i]) < bestSplit)
                scratch[l++] = ids[i];
            else
                scratch[r++] = ids[i];
        }
    }
#pragma omp parallel for schedule(static)
    for (std::int64_t i = t.begin; i < static_cast<std::int64_t>(t.end); ++i) ids[i] = scratch[i];
    return t.begin + totalLeft;
}

}  // namespace

Bvh buildBvh(std::span<const Bounds3f> boxes, std::span<const Vec3f> centers,
             const BvhBuildOptions& options) {
    UVR_CHECK(boxes.size() == centers.size(), "boxes and centres differ in count");
    UVR_CHECK(boxes.size() < 0xffffffffull, "too many primitives for a 32-bit BVH");
    Bvh bvh;
    const std::uint32_t n = static_cast<std::uint32_t>(boxes.size());
    if (n == 0) return bvh;
    bvh.primIds.resize(n);
    std::uint32_t* ids = bvh.primIds.data();
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < static_cast<std::int64_t>(n); ++i)
        ids[i] = static_cast<std::uint32_t>(i);
    if (n <= kSubtreePrims) {
        buildSubtree(boxes, centers, ids, {0, 0, n, 1}, options, bvh.nodes);
        return bvh;
    }
    // Step 1: the top of the tree, one large node at a time, each split by parallel passes;
    // nodes of at most kSubtreePrims primitives become subtree jobs.
    bvh.nodes.emplace_back();
    std::vector<Task> stack{{0, 0, n, 1}}, jobs;
    ScratchVector<std::uint32_t> scratch(n);
    while (!stack.empty()) {
        const Task t = stack.back();
        stack.pop_back();
        if (t.end - t.begin <= kSubtreePrims) {
            jobs.push_back(t);
            continue;
        }
        Bounds3f box;
        const std::uint32_t mid = splitLarge(boxes, centers, ids, scratch.data(), t, options, box);
        if (mid == t.end) {
            jobs.push_back(t);
            continue;
        }
        const std::uint32_t left = static_cast<std::uint32_t>(bvh.nodes.size());
        bvh.nodes[t.node] = {box, left, 0};
        bvh.nodes.emplace_back();
        bvh.nodes.emplace_back();
        stack.push_back({left + 1, mid, t.end, t.depth + 1});
        stack.push_back({left, t.begin, mid, t.depth + 1});
    }
    scratch = {};
    // Step 2: the subtrees, in parallel, each into its own node list.
    const std::int64_t jobCount = static_cast<std::int64_t>(jobs.size());
    std::vector<std::vector<BvhNode>> local(jobs.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t j = 0; j < jobCount; ++j)
        buildSubtree(boxes, centers, ids, jobs[j], options, local[j]);
    // Step 3: append them in job order (each subtree's root replaces its placeholder).
    std::vector<std::size_t> base(jobs.size() + 1, bvh.nodes.size());
    for (std::int64_t j = 0; j < jobCount; ++j) base[j + 1] = base[j] + local[j].size() - 1;
    UVR_CHECK(base[jobCount] < 0xffffffffull, "too many BVH nodes for 32-bit indices");
    bvh.nodes.resize(base[jobCount]);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t j = 0; j < jobCount; ++j) {
        const std::uint32_t offset = static_cast<std::uint32_t>(base[j]) - 1;
        for (std::size_t i = 0; i < local[j].size(); ++i) {
            BvhNode node = local[j][i];
            if (node.count == 0) node.first += offset;
            bvh.nodes[i == 0 ? jobs[j].node : offset + i] = node;
        }
        local[j] = {};
    }
    return bvh;
}

void tetBoxesAndCenters(const TetMesh& mesh, std::vector<Bounds3f>& boxes,
                        std::vector<Vec3f>& centers) {
    const std::int64_t n = static_cast<std::int64_t>(mesh.cellCount());
    const TetMeshView view = mesh.view();
    boxes.resize(n);
    centers.resize(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < n; ++t) {
        const Bounds3f b = view.cellBounds(std::uint64_t(t));
        boxes[t] = b;
        centers[t] = b.center();
    }
}

Bvh buildCellTree(const TetMesh& mesh, std::uint32_t leafCells, const FractionFn& progress) {
    Bvh bvh;
    const std::uint64_t n = mesh.cellCount();
    if (n == 0) {
        if (progress) progress(1.0);
        return bvh;
    }
    UVR_CHECK(leafCells > 0, "buildCellTree: leaves of 0 cells");
    const std::uint64_t leaves = (n + leafCells - 1) / leafCells;
    UVR_CHECK(2 * leaves - 1 < 0xffffffffull, "cell tree nodes exceed 32-bit indices");
    bvh.nodes.resize(2 * leaves - 1);
    std::vector<std::uint32_t> leafNode(leaves);
    // Structure: the node at `node` covers runs [b, e); its children take slots next and
    // next + 1, the left one's descendants the 2 k - 2 slots after them (k: its runs).
    struct Job {
        std::uint32_t node;
        std::uint64_t b, e;
        std::uint32_t next;
    };
    std::vector<Job> stack{{0, 0, leaves, 1}};
    while (!stack.empty()) {
        const Job j = stack.back();
        stack.pop_back();
        BvhNode& node = bvh.nodes[j.node];
        if (j.e - j.b == 1) {
            node.first = static_cast<std::uint32_t>(j.b * leafCells);
            node.count =
                static_cast<std::uint32_t>(std::min<std::uint64_t>(leafCells, n - j.b * leafCells));
            leafNode[j.b] = j.node;
            continue;
        }
        const std::uint64_t mid = j.b + (j.e - j.b) / 2;
        node.first = j.next;
        node.count = 0;
        stack.push_back({j.next, j.b, mid, j.next + 2});
        stack.push_back(
            {j.next + 1, mid, j.e, j.next + static_cast<std::uint32_t>(2 * (mid - j.b))});
    }
    // Boxes: the runs' in parallel, then the inner nodes from the last (children follow their
    // parent).
    const TetMeshView view = mesh.view();
    // Progress: the structure to 0.2, the runs' boxes to 0.9, the inner boxes to 1.
    if (progress) progress(0.2);
    ProgressCounter boxed(progress, std::int64_t(leaves), 0.2, 0.9);
#pragma omp parallel for schedule(static)
    for (std::int64_t l = 0; l < std::int64_t(leaves); ++l) {
        BvhNode& node = bvh.nodes[leafNode[l]];
        Bounds3f box;
        for (std::uint32_t c = node.first; c < node.first + node.count; ++c)
            box.extend(view.cellBounds(c));
        node.box = box;
        boxed.tick(l);
    }
    boxed.finish();
    for (std::int64_t i = std::int64_t(bvh.nodes.size()) - 1; i >= 0; --i) {
        BvhNode& node = bvh.nodes[i];
        if (node.count > 0) continue;
        node.box = bvh.nodes[node.first].box;
        node.box.extend(bvh.nodes[node.first + 1].box);
    }
    if (progress) progress(1.0);
    return bvh;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/accel/kd_partitions.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <optional>
#include <span>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"

namespace uvr {

namespace {

/// Padding of shrunk boxes, relative to the mesh diagonal.
constexpr float kBoxPadding = 1e-6f;
/// Nodes with more cells are split by data-parallel passes; smaller ones are whole subtrees built
/// by one thread each. Fixed (not derived from the thread count), so the partitions are the same
/// whatever the number of threads.
constexpr std::size_t kSubtreeCells = 1u << 18;
/// Cells per chunk of a data-parallel pass.
constexpr std::int64_t kChunk = 1 << 14;

/// Per-cell boxes and centres.
struct CellData {
    std::vector<Bounds3f> boxes;
    std::vector<Vec3f> centers;
};

/// A node to split: its k-d node index, region, cells and depth.
struct Task {
    std::uint32_t node;
    Bounds3f region;
    std::vector<std::uint32_t> cells;
    int depth;
};

/// A partition awaiting its description: the shrunk box and the cells.
struct Leaf {
    Bounds3f shrunk;
    std::vector<std::uint32_t> cells;
};

/// A subtree built by one thread: nodes with local indices (node 0 is its root; a leaf's child
/// field names its entry of `leaves`).
struct LocalTree {
    std::vector<KdNode> nodes;
    std::vector<Leaf> leaves;
};

/// Makes node task.node an inner node splitting `axis` at `plane` with two new children in
/// nodes, and pushes the children's tasks (below the plane last, so it is taken first).
void splitNode(std::vector<KdNode>& nodes, std::vector<Task>& stack, const Task& task, int axis,
               float plane, std::vector<std::uint32_t>&& left, std::vector<std::uint32_t>&& right) {
    const std::uint32_t child = static_cast<std::uint32_t>(nodes.size());
    nodes[task.node].split = plane;
    nodes[task.node].bits = (child << 2) | static_cast<std::uint32_t>(axis);
    nodes.emplace_back();
    nodes.emplace_back();
    Bounds3f below = task.region, above = task.region;
    below.hi[axis] = plane;
    above.lo[axis] = plane;
    stack.push_back({child + 1, above, std::move(right), task.depth + 1});
    stack.push_back({child, below, std::move(left), task.depth + 1});
}

/// A partition's padded shrunk box and cell count (its value range comes later, from
/// computePartitionValueRanges).
void describePartition(const Bounds3f& shrunk, std::span<const std::uint32_t> cells, Vec3f pad,
                       KdPartition& part) {
    // Widened by a hair so that samples exactly on a cell face bounding the box are not lost to
    // rounding in the ray-box clip (it only admits samples that then find no cell).
    part.box = shrunk;
    if (!shrunk.empty()) part.box.lo = part.box.lo - pad, part.box.hi = part.box.hi + pad;
    part.cellCount = static_cast<std::uint32_t>(cells.size());
}

/// The k-th smallest centre coordinate on `axis` of the cells (what std::nth_element picks), by
/// parallel radix selection: four 8-bit histogram passes from the most significant digit.
float parallelKth(const CellData& data, const std::vector<std::uint32_t>& cells, int axis,
                  std::size_t k) {
    const std::int64_t count = static_cast<std::int64_t>(cells.size());
    ScratchVector<std::uint32_t> keys(cells.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < count; ++i)
        keys[i] = kdsplit::floatKey(data.centers[cells[i]][axis]);
    const std::int64_t chunks = (count + kChunk - 1) / kChunk;
    std::vector<std::uint64_t> histograms(chunks * 256);
    std::uint32_t prefix = 0, mask = 0;
    for (int shift = 24; shift >= 0; shift -= 8) {
        std::fill(histograms.begin(), histograms.end(), 0u);
#pragma omp parallel for schedule(dynamic, 1)
        for (std::int64_t c = 0; c < chunks; ++c) {
            std::uint64_t* h = histograms.data() + c * 256;
            const std::int64_t end = std::min(count, (c + 1) * kChunk);
            for (std::int64_t i = c * kChunk; i < end; ++i)
                if ((keys[i] & mask) == prefix) ++h[(keys[i] >> shift) & 255u];
        }
        std::uint64_t total[256] = {};
        for (std::int64_t c = 0; c < chunks; ++c)
            for (int d = 0; d < 256; ++d) total[d] += histograms[c * 256 + d];
        int digit = 0;
        while (k >= total[digit]) k -= total[digit++];
        prefix |= static_cast<std::uint32_t>(digit) << shift;
        mask |= 255u << shift;
    }
    return kdsplit::keyFloat(prefix);
}

/// Splits a large task with data-parallel passes (Morrical et al. 2019, Sec. 2.1: median of the
/// cell centres on the longest axis of the occupied region). Returns false when the node should
/// be left to buildSubtree (which then makes it a leaf); else fills the children's cell lists
/// (in the parent's order), the axis and the plane.
bool splitLarge(const CellData& data, const Task& task, const KdBuildOptions& options,
                std::vector<std::uint32_t>& left, std::vector<std::uint32_t>& right, int& axis,
                float& plane) {
    const std::int64_t count = static_cast<std::int64_t>(task.cells.size());
    const std::int64_t chunks = (count + kChunk - 1) / kChunk;
    std::vector<Bounds3f> chunkBounds(chunks);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const std::int64_t end = std::min(count, (c + 1) * kChunk);
        for (std::int64_t i = c * kChunk; i < end; ++i)
            chunkBounds[c].extend(data.boxes[task.cells[i]]);
    }
    Bounds3f cellBounds;
    for (const Bounds3f& b : chunkBounds) cellBounds.extend(b);
    const Bounds3f shrunk = kdsplit::shrunkRegion(task.region, cellBounds);
    if (!kdsplit::wantsSplit(count, task.depth, shrunk, options.leafCells, options.maxDepth))
        return false;
    axis = shrunk.longestAxis();
    plane = parallelKth(data, task.cells, axis, static_cast<std::size_t>(count / 2));
    // A cell touching the plane goes to both sides (see buildSubtree).
    std::vector<std::uint64_t> before(2 * (chunks + 1), 0u);  // [left, right] per chunk
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const std::int64_t end = std::min(count, (c + 1) * kChunk);
        std::uint64_t l = 0, r = 0;
        for (std::int64_t i = c * kChunk; i < end; ++i) {
            l += kdsplit::goesBelow(data.boxes[task.cells[i]], axis, plane);
            r += kdsplit::goesAbove(data.boxes[task.cells[i]], axis, plane);
        }
        before[2 * (c + 1)] = l;
        before[2 * (c + 1) + 1] = r;
    }
    for (std::int64_t c = 0; c < chunks; ++c) {
        before[2 * (c + 1)] += before[2 * c];
        before[2 * (c + 1) + 1] += before[2 * c + 1];
    }
    const std::uint64_t nl = before[2 * chunks], nr = before[2 * chunks + 1];
    if (!kdsplit::keepsSplit(task.region, axis, plane, nl, nr, count)) return false;
    left.resize(nl);
    right.resize(nr);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        const std::int64_t end = std::min(count, (c + 1) * kChunk);
        std::uint64_t l = before[2 * c], r = before[2 * c + 1];
        for (std::int64_t i = c * kChunk; i < end; ++i) {
            const std::uint32_t cell = task.cells[i];
            if (kdsplit::goesBelow(data.boxes[cell], axis, plane)) left[l++] = cell;
            if (kdsplit::goesAbove(data.boxes[cell], axis, plane)) right[r++] = cell;
        }
    }
    return true;
}

/// Builds the k-d subtree of a task with one thread (median splits as splitLarge; a node whose
/// split would not reduce the larger side below 90% of its cells becomes a leaf).
LocalTree buildSubtree(const CellData& data, Task root, const KdBuildOptions& options) {
    LocalTree out;
    out.nodes.emplace_back();
    root.node = 0;
    std::vector<Task> stack;
    stack.push_back(std::move(root));
    while (!stack.empty()) {
        Task task = std::move(stack.back());
        stack.pop_back();
        const std::size_t count = task.cells.size();
        Bounds3f cellBounds;
        for (std::uint32_t c : task.cells) cellBounds.extend(data.boxes[c]);
        const Bounds3f shrunk = kdsplit::shrunkRegion(task.region, cellBounds);
        // Median split of the cell centres along the longest axis of the occupied region.
        bool split =
            kdsplit::wantsSplit(count, task.depth, shrunk, options.leafCells, options.maxDepth);
        std::vector<std::uint32_t> left, right;
        int axis = 0;
        float plane = 0.f;
        if (split) {
            axis = shrunk.longestAxis();
            // The median value of a copy: the children keep the parent's cell order.
            std::vector<float> keys(count);
            for (std::size_t i = 0; i < count; ++i) keys[i] = data.centers[task.cells[i]][axis];
            auto mid = keys.begin() + count / 2;
            std::nth_element(keys.begin(), mid, keys.end());
            plane = *mid;
            // A cell touching the plane goes to both sides, so every point of a child's closed
            // region that lies in a cell finds that cell in the child's list.
            for (std::uint32_t c : task.cells) {
                if (kdsplit::goesBelow(data.boxes[c], axis, plane)) left.push_back(c);
                if (kdsplit::goesAbove(data.boxes[c], axis, plane)) right.push_back(c);
            }
            split = kdsplit::keepsSplit(task.region, axis, plane, left.size(), right.size(), count);
        }
        if (split) {
            task.cells = {};
            splitNode(out.nodes, stack, task, axis, plane, std::move(left), std::move(right));
            continue;
        }
        out.nodes[task.node].bits = (static_cast<std::uint32_t>(out.leaves.size()) << 2) | 3u;
        out.leaves.push_back({shrunk, std::move(task.cells)});
    }
    return out;
}

}  // namespace

KdPartitions buildKdPartitions(const TetMesh& mesh, const KdBuildOptions& options,
                               const FractionFn& progress) {
    const auto start = std::chrono::steady_clock::now();
    // Progress: boxes to 0.1, the top of the tree to 0.45 (cells passed through splitLarge, about
    // n per level), the subtrees to 0.9 (their cells), the cell lists and value ranges to 1.
    constexpr double kBoxesEnd = 0.1, kTopEnd = 0.45, kSubtreesEnd = 0.9;
    UVR_CHECK(options.leafCells >= 1, "leaf size must be positive");
    const std::size_t n = mesh.cellCount();
    UVR_CHECK(n < (1ull << 30), "too many cells for k-d partitions");
    const TetMeshView view = mesh.view();
    KdPartitions kd;
    kd.bounds = mesh.bounds;
    kd.leafCells = options.leafCells;
    // Step 1: per-cell boxes and centres (the geometry alone decides the partitions).
    CellData data;
    const bool needBoxes = !options.splitter;  // for the CPU's splits
    const std::int64_t tetCount = static_cast<std::int64_t>(n);
    if (needBoxes) {
        data.boxes.resize(n), data.centers.resize(n);
        ProgressCounter boxed(progress, tetCount, 0.0, kBoxesEnd);
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < tetCount; ++t) {
            const Bounds3f box = view.cellBounds(std::uint64_t(t));
            data.boxes[t] = box, data.centers[t] = box.center();
            boxed.tick(t);
        }
        boxed.finish();
    }
    std::vector<Leaf> leaves;  // the CPU's leaves; or, from a splitter, `tree`
    std::optional<KdTree> tree;
    if (options.splitter) {
        // Steps 2-4 elsewhere (the GPU): the same splits and leaves.
        tree = options.splitter(mesh, options, subRange(progress, 0.0, kSubtreesEnd));
        kd.nodes = std::move(tree->nodes);
    } else {
        // Step 2: the top of the tree, one large node at a time, split by parallel passes; nodes of
        // at most kSubtreeCells cells become subtree jobs.
        kd.nodes.emplace_back();
        std::vector<Task> stack, jobs;
        const int topLevels = static_cast<int>(
            std::ceil(std::log2(std::max(1.0, double(n) / double(kSubtreeCells)))));
        ProgressCounter topDone(progress, std::int64_t(n) * std::max(topLevels, 1), kBoxesEnd,
                                kTopEnd);
        if (const std::optional<KdSubtreeRoot>& root = options.root) {
            // A larger tree's node: the cells it hands that node, in id order.
            std::vector<std::uint32_t> reaching;
            for (std::int64_t t = 0; t < tetCount; ++t) {
                const Bounds3f& b = data.boxes[t];
                bool reaches = true;
                for (int a = 0; a < 3; ++a)
                    reaches =
                        reaches && b.lo[a] <= root->region.hi[a] && b.hi[a] >= root->region.lo[a];
                if (reaches) reaching.push_back(static_cast<std::uint32_t>(t));
            }
            stack.push_back({0, root->region, std::move(reaching), root->depth});
        } else {
            std::vector<std::uint32_t> all(n);
#pragma omp parallel for schedule(static)
            for (std::int64_t t = 0; t < tetCount; ++t) all[t] = static_cast<std::uint32_t>(t);
            stack.push_back({0, mesh.bounds, std::move(all), 0});
        }
        while (!stack.empty()) {
            Task task = std::move(stack.back());
            stack.pop_back();
            std::vector<std::uint32_t> left, right;
            int axis = 0;
            float plane = 0.f;
            if (task.cells.size() <= kSubtreeCells ||
                !splitLarge(data, task, options, left, right, axis, plane)) {
                jobs.push_back(std::move(task));
                continue;
            }
            topDone.add(std::int64_t(task.cells.size()));
            splitNode(kd.nodes, stack, task, axis, plane, std::move(left), std::move(right));
        }
        topDone.finish();
        // Step 3: the subtrees, in parallel.
        const std::int64_t jobCount = static_cast<std::int64_t>(jobs.size());
        std::vector<LocalTree> local(jobs.size());
        std::int64_t jobCells = 0;
        for (const Task& job : jobs) jobCells += std::int64_t(job.cells.size());
        ProgressCounter subtreesDone(progress, jobCells, kTopEnd, kSubtreesEnd);
#pragma omp parallel for schedule(dynamic, 1)
        for (std::int64_t j = 0; j < jobCount; ++j) {
            const std::uint32_t node = jobs[j].node;
            const std::int64_t cells = std::int64_t(jobs[j].cells.size());
            local[j] = buildSubtree(data, std::move(jobs[j]), options);
            jobs[j].node = node;
            subtreesDone.add(cells);
        }
        subtreesDone.finish();
        // Step 4: append the subtrees in job order (each root replaces its placeholder) and number
        // their leaves.
        for (std::int64_t j = 0; j < jobCount; ++j) {
            const std::uint32_t nodeOffset = static_cast<std::uint32_t>(kd.nodes.size()) - 1;
            const std::uint32_t leafOffset = static_cast<std::uint32_t>(leaves.size());
            for (std::size_t i = 0; i < local[j].nodes.size(); ++i) {
                KdNode node = local[j].nodes[i];
                const std::uint32_t c = node.child() + (node.isLeaf() ? leafOffset : nodeOffset);
                node.bits = (c << 2) | (node.bits & 3u);
                if (i == 0)
                    kd.nodes[jobs[j].node] = node;
                else
                    kd.nodes.push_back(node);
            }
            for (Leaf& leaf : local[j].leaves) leaves.push_back(std::move(leaf));
            local[j] = {};
        }
    }
    kd.treeSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // Step 5: cell-list offsets (known from the leaves).
    const std::int64_t leafCount =
        static_cast<std::int64_t>(tree ? tree->leafShrunk.size() : leaves.size());
    auto cellsOf = [&](std::int64_t p) -> std::span<const std::uint32_t> {
        if (!tree) return leaves[p].cells;
        return std::span<const std::uint32_t>(tree->leafCells)
            .subspan(tree->leafBegin[p], tree->leafBegin[p + 1] - tree->leafBegin[p]);
    };
    auto shrunkOf = [&](std::int64_t p) { return tree ? tree->leafShrunk[p] : leaves[p].shrunk; };
    kd.partitions.resize(leafCount);
    std::uint64_t cells = 0;
    for (std::int64_t p = 0; p < leafCount; ++p) {
        kd.partitions[p].firstCell = static_cast<std::uint32_t>(cells);
        cells += cellsOf(p).size();
        UVR_CHECK(cells < 0xffffffffull, "partition cell lists exceed 32-bit indices");
    }
    // Step 6: each partition's padded shrunk box and its cell list, in partition order.
    const Vec3f pad = Vec3f(
        kBoxPadding * (options.root ? options.root->paddingDiagonal : mesh.bounds.diagonal()));
    if (!tree) kd.cells.resize(cells);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t p = 0; p < leafCount; ++p) {
        describePartition(shrunkOf(p), cellsOf(p), pad, kd.partitions[p]);
        if (tree) continue;
        std::copy(leaves[p].cells.begin(), leaves[p].cells.end(),
                  kd.cells.begin() + kd.partitions[p].firstCell);
        leaves[p] = {};
    }
    if (tree) kd.cells = std::move(tree->leafCells);  // already in partition order
    computePartitionValueRanges(mesh, kd);
    if (progress) progress(1.0);
    kd.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return kd;
}

void computePartitionValueRanges(const TetMesh& mesh, KdPartitions& kd) {
    const bool cellData = mesh.association == Association::Cell;
    const std::int64_t n = static_cast<std::int64_t>(kd.partitions.size());
    const TetMeshView view = mesh.view();
#pragma omp parallel for schedule(dynamic, 16)
    for (std::int64_t p = 0; p < n; ++p) {
        KdPartition& part = kd.partitions[p];
        float lo = INFINITY, hi = -INFINITY;
        for (std::uint32_t i = 0; i < part.cellCount; ++i) {
            const std::uint32_t t = kd.cells[part.firstCell + i];
            if (cellData) {
                const float v = mesh.values[t];
                if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
                continue;
            }
            std::uint32_t ids[kMaxCellCorners];
            const int corners = view.corners(t, ids);
            for (int k = 0; k < corners; ++k) {
                const float v = mesh.values[ids[k]];
                if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
            }
        }
        part.valueMin = lo <= hi ? lo : 0.f;
        part.valueMax = lo <= hi ? hi : 0.f;
    }
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/accel/kd_partitions.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "uvr/core/error.h"

namespace uvr {

namespace {

struct Task {
    std::uint32_t node;
    Bounds3f region;
    std::vector<std::uint32_t> cells;
    int depth;
};

/// Padding of shrunk boxes, relative to the mesh diagonal.
constexpr float kBoxPadding = 1e-6f;

Bounds3f intersect(const Bounds3f& a, const Bounds3f& b) {
    Bounds3f r;
    r.lo = vmax(a.lo, b.lo);
    r.hi = vmin(a.hi, b.hi);
    return r;
}

}  // namespace

KdPartitions buildKdPartitions(const TetMesh& mesh, const KdBuildOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    UVR_CHECK(options.leafCells >= 1, "leaf size must be positive");
    const std::size_t n = mesh.tets.size();
    UVR_CHECK(n < (1ull << 30), "too many tetrahedra for k-d partitions");
    KdPartitions kd;
    kd.bounds = mesh.bounds;
    kd.leafCells = options.leafCells;
    // Per-cell boxes, centres and finite value ranges.
    std::vector<Bounds3f> boxes(n);
    std::vector<Vec3f> centers(n);
    std::vector<float> vmin(n, INFINITY), vmax(n, -INFINITY);
    const bool cellData = mesh.association == Association::Cell;
    for (std::size_t t = 0; t < n; ++t) {
        for (std::uint32_t v : mesh.tets[t].v) {
            boxes[t].extend(mesh.points[v]);
            if (!cellData && std::isfinite(mesh.values[v])) {
                vmin[t] = std::min(vmin[t], mesh.values[v]);
                vmax[t] = std::max(vmax[t], mesh.values[v]);
            }
        }
        if (cellData && std::isfinite(mesh.values[t])) vmin[t] = vmax[t] = mesh.values[t];
        centers[t] = boxes[t].center();
    }
    kd.nodes.emplace_back();
    std::vector<Task> stack;
    {
        std::vector<std::uint32_t> all(n);
        for (std::size_t t = 0; t < n; ++t) all[t] = static_cast<std::uint32_t>(t);
        stack.push_back({0, mesh.bounds, std::move(all), 0});
    }
    std::vector<Bounds3f> leafBoxes;
    std::vector<Vec3f> leafCenters;
    while (!stack.empty()) {
        Task task = std::move(stack.back());
        stack.pop_back();
        const std::size_t count = task.cells.size();
        Bounds3f cellBounds;
        for (std::uint32_t c : task.cells) cellBounds.extend(boxes[c]);
        const Bounds3f shrunk = intersect(task.region, cellBounds);
        // Median split of the cell centres along the longest axis of the occupied region.
        bool split = count > options.leafCells && task.depth < options.maxDepth && !shrunk.empty();
        std::vector<std::uint32_t> left, right;
        int axis = 0;
        float plane = 0.f;
        if (split) {
            axis = shrunk.longestAxis();
            auto mid = task.cells.begin() + count / 2;
            std::nth_element(task.cells.begin(), mid, task.cells.end(),
                             [&](std::uint32_t a, std::uint32_t b) {
                                 return centers[a][axis] < centers[b][axis];
                             });
            plane = centers[*mid][axis];
            // A cell touching the plane goes to both sides, so every point of a child's closed
            // region that lies in a cell finds that cell in the child's list.
            for (std::uint32_t c : task.cells) {
                if (boxes[c].lo[axis] <= plane) left.push_back(c);
                if (boxes[c].hi[axis] >= plane) right.push_back(c);
            }
            const std::size_t larger = std::max(left.size(), right.size());
            split = plane > task.region.lo[axis] && plane < task.region.hi[axis] &&
                    larger * 10 <= count * 9;
        }
        if (split) {
            const std::uint32_t child = static_cast<std::uint32_t>(kd.nodes.size());
            kd.nodes[task.node].split = plane;
            kd.nodes[task.node].bits = (child << 2) | static_cast<std::uint32_t>(axis);
            kd.nodes.emplace_back();
            kd.nodes.emplace_back();
            Bounds3f below = task.region, above = task.region;
            below.hi[axis] = plane;
            above.lo[axis] = plane;
            task.cells = {};
            stack.push_back({child + 1, above, std::move(right), task.depth + 1});
            stack.push_back({child, below, std::move(left), task.depth + 1});
            continue;
        }
        // Leaf: shrunk box, whole-cell value range, and a BVH over its cells.
        KdPartition part;
        // Widened by a hair so that samples exactly on a cell face bounding the box are not lost
        // to rounding in the ray-box clip (it only admits samples that then find no cell).
        part.box = shrunk;
        const Vec3f pad = Vec3f(kBoxPadding * mesh.bounds.diagonal());
        if (!shrunk.empty()) part.box.lo = part.box.lo - pad, part.box.hi = part.box.hi + pad;
        float lo = INFINITY, hi = -INFINITY;
        for (std::uint32_t c : task.cells) lo = std::min(lo, vmin[c]), hi = std::max(hi, vmax[c]);
        part.valueMin = lo <= hi ? lo : 0.f;
        part.valueMax = lo <= hi ? hi : 0.f;
        part.firstCell = static_cast<std::uint32_t>(kd.cells.size());
        part.cellCount = static_cast<std::uint32_t>(count);
        part.bvhRoot = static_cast<std::uint32_t>(kd.bvhNodes.size());
        leafBoxes.resize(count);
        leafCenters.resize(count);
        for (std::size_t i = 0; i < count; ++i) {
            leafBoxes[i] = boxes[task.cells[i]];
            leafCenters[i] = centers[task.cells[i]];
        }
        const Bvh bvh = buildBvh(leafBoxes, leafCenters);
        for (BvhNode node : bvh.nodes) {
            node.first += node.count > 0 ? part.firstCell : part.bvhRoot;
            kd.bvhNodes.push_back(node);
        }
        for (std::uint32_t local : bvh.primIds) kd.cells.push_back(task.cells[local]);
        kd.nodes[task.node].bits = (static_cast<std::uint32_t>(kd.partitions.size()) << 2) | 3u;
        kd.partitions.push_back(part);
    }
    UVR_CHECK(kd.cells.size() < 0xffffffffull, "partition cell lists exceed 32-bit indices");
    kd.buildSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return kd;
}

}  // namespace uvr

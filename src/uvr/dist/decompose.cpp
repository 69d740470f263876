// SPDX-License-Identifier: MIT
#include "uvr/dist/decompose.h"

#include <algorithm>
#include <numeric>
#include <string>

#include "uvr/core/error.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

std::vector<double> partitionCosts(const KdPartitions& kd) {
    const std::size_t n = kd.partitions.size();
    std::vector<double> cost(n, 0.0);
    double cells = 0.0, volume = 0.0;
    const auto volumeOf = [](const Bounds3f& b) {
        if (b.empty()) return 0.0;
        const Vec3f e = b.extent();
        return double(e.x) * e.y * e.z;
    };
    for (const KdPartition& p : kd.partitions) cells += p.cellCount, volume += volumeOf(p.box);
    for (std::size_t p = 0; p < n; ++p) {
        const double c = cells > 0.0 ? kd.partitions[p].cellCount / cells : 0.0;
        const double v = volume > 0.0 ? volumeOf(kd.partitions[p].box) / volume : 0.0;
        cost[p] = 0.5 * c + 0.5 * v;
    }
    return cost;
}

Decomposition decompose(const KdPartitions& kd, const std::vector<double>& partitionCost,
                        int ranks) {
    UVR_CHECK(ranks >= 1, "rank count " << ranks);
    UVR_CHECK(partitionCost.size() == kd.partitions.size(), "partition costs missing");
    if (kd.nodes.empty() || kd.partitions.size() < std::size_t(ranks))
        throwError(ErrorKind::Argument, "",
                   "the mesh has " + std::to_string(kd.partitions.size()) +
                       " k-d partitions, fewer than the " + std::to_string(ranks) +
                       " ranks: run on at most " + std::to_string(kd.partitions.size()) + " ranks");
    // Each node's cost: its partitions' (children follow their parents in the layout).
    const std::size_t nodeCount = kd.nodes.size();
    std::vector<double> nodeCost(nodeCount, 0.0);
    for (std::size_t i = nodeCount; i-- > 0;) {
        const KdNode n = kd.nodes[i];
        nodeCost[i] =
            n.isLeaf() ? partitionCost[n.child()] : nodeCost[n.child()] + nodeCost[n.child() + 1];
    }
    // The cut: the costliest inner node replaced by its children, `ranks` - 1 times.
    std::vector<std::uint32_t> cut{0};
    while (cut.size() < std::size_t(ranks)) {
        std::size_t best = cut.size();
        for (std::size_t i = 0; i < cut.size(); ++i)
            if (!kd.nodes[cut[i]].isLeaf() &&
                (best == cut.size() || nodeCost[cut[i]] > nodeCost[cut[best]]))
                best = i;
        UVR_CHECK(best < cut.size(), "no inner node left to cut");
        const std::uint32_t child = kd.nodes[cut[best]].child();
        cut[best] = child;
        cut.insert(cut.begin() + std::ptrdiff_t(best) + 1, child + 1);
    }
    // The tree above the cut, depth first from the root (the same left-to-right order as the
    // cut, which names the ranks); regions from the whole tree's.
    const std::vector<Bounds3f> regions = kdNodeRegions(kd.nodes, kd.bounds);
    Decomposition d;
    d.rankTree.emplace_back();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{0u, 0u}};  // whole, ours
    while (!stack.empty()) {
        const auto [from, to] = stack.back();
        stack.pop_back();
        const auto inCut = std::find(cut.begin(), cut.end(), from);
        if (inCut != cut.end()) {
            const std::uint32_t rank = static_cast<std::uint32_t>(inCut - cut.begin());
            d.rankTree[to].bits = (rank << 2) | 3u;
            continue;
        }
        const KdNode n = kd.nodes[from];
        const std::uint32_t child = static_cast<std::uint32_t>(d.rankTree.size());
        d.rankTree[to].split = n.split;
        d.rankTree[to].bits = (child << 2) | static_cast<std::uint32_t>(n.axis());
        d.rankTree.emplace_back();
        d.rankTree.emplace_back();
        stack.push_back({n.child() + 1, child + 1});
        stack.push_back({n.child(), child});
    }
    for (std::uint32_t node : cut) {
        d.node.push_back(node);
        d.regions.push_back(regions[node]);
        d.cost.push_back(nodeCost[node]);
    }
    return d;
}

std::vector<int> visibilityOrder(const Decomposition& d, bool parallel, Vec3f eye, Vec3f dir) {
    std::vector<int> order;
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
        const KdNode n = d.rankTree[stack.back()];
        stack.pop_back();
        if (n.isLeaf()) {
            order.push_back(static_cast<int>(n.child()));
            continue;
        }
        const int a = n.axis();
        // The near side: where the eye is (perspective), or the side rays enter first.
        const bool belowFirst = parallel ? dir[a] >= 0.f : eye[a] < n.split;
        stack.push_back(n.child() + (belowFirst ? 1u : 0u));
        stack.push_back(n.child() + (belowFirst ? 0u : 1u));
    }
    return order;
}

WholeMesh describeWholeMesh(const MeshView& mesh, const ScalarField& field,
                            const PrepareOptions& options, const ProgressFn& progress) {
    WholeMesh w;
    if (progress)
        progress("splitting the whole mesh's " + std::to_string(mesh.cellCount()) +
                 " cells for its k-d tree");
    TetrahedralizeOptions cells = options.cells;
    cells.spatialOrder = false;  // the tree does not depend on the cells' order
    cells.sorter = nullptr;
    const TetMesh tets = tetrahedralize(mesh, field, cells, progress.fraction);
    if (progress) progress("building the whole mesh's k-d tree");
    KdBuildOptions kd = kdBuildOptions(tets, options);
    kd.splitter = nullptr;
    w.kd = buildKdPartitions(tets, kd, progress.fraction);
    w.frame = tets.frame;
    w.bounds = tets.bounds;
    w.valueMin = tets.valueMin, w.valueMax = tets.valueMax;
    w.defaultStep = defaultStep(tets);
    w.sourceCells = mesh.cellCount();
    w.autoCpu = autoMethod(tets, false);
    w.autoGpu = autoMethod(tets, true);
    return w;
}

RankPiece extractPiece(const MeshView& mesh, const ScalarField& field, const WholeMesh& whole,
                       const Decomposition& d, int rank, float ghostWidth) {
    UVR_CHECK(rank >= 0 && std::size_t(rank) < d.regions.size(), "rank " << rank);
    const Bounds3f region = d.regions[rank];
    Bounds3f reach = region;
    reach.lo = reach.lo - Vec3f(ghostWidth), reach.hi = reach.hi + Vec3f(ghostWidth);
    // The cells whose bounds (in rendering units) reach the widened box.
    const std::uint64_t cellCount = mesh.cellCount();
    std::vector<std::uint8_t> keep(cellCount, 0);
    std::vector<std::uint8_t> used(mesh.pointCount(), 0);
    const std::int64_t n = static_cast<std::int64_t>(cellCount);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < n; ++c) {
        Bounds3f box;
        for (std::uint32_t id : mesh.cell(std::uint64_t(c))) {
            double p[3];
            whole.frame.toLocal(mesh.points[id], p);
            box.extend(Vec3f(float(p[0]), float(p[1]), float(p[2])));
        }
        bool reaches = !box.empty();
        for (int a = 0; a < 3; ++a)
            reaches = reaches && box.lo[a] <= reach.hi[a] && box.hi[a] >= reach.lo[a];
        keep[c] = reaches ? 1 : 0;
    }
    for (std::uint64_t c = 0; c < cellCount; ++c)
        if (keep[c])
            for (std::uint32_t id : mesh.cell(c)) used[id] = 1;
    // The points in the whole mesh's order (so cells split as one process splits them).
    RankPiece out;
    std::vector<std::uint32_t> newId(mesh.pointCount(), 0);
    for (std::uint64_t i = 0; i < mesh.pointCount(); ++i)
        if (used[i]) {
            newId[i] = static_cast<std::uint32_t>(out.mesh.points.size());
            out.mesh.points.push_back(mesh.points[i]);
        }
    out.field.name = field.name;
    out.field.association = field.association;
    out.field.choice = field.choice;
    const bool pointData = field.association == Association::Point;
    if (pointData)
        for (std::uint64_t i = 0; i < mesh.pointCount(); ++i)
            if (used[i]) out.field.values.push_back(field.values[i]);
    std::vector<std::uint32_t> ids;
    for (std::uint64_t c = 0; c < cellCount; ++c) {
        if (!keep[c]) continue;
        ids.clear();
        for (std::uint32_t id : mesh.cell(c)) ids.push_back(newId[id]);
        out.mesh.addCell(mesh.cellTypes[c], ids);
        if (!pointData) out.field.values.push_back(field.values[c]);
    }
    // What the rank's preparation takes from the whole mesh.
    auto piece = std::make_shared<MeshPiece>();
    piece->rank = rank;
    piece->ranks = static_cast<int>(d.regions.size());
    piece->region = region;
    piece->tree = kdSubtree(whole.kd, d.node[rank]);
    piece->frame = whole.frame;
    piece->bounds = whole.bounds;
    piece->valueMin = whole.valueMin, piece->valueMax = whole.valueMax;
    piece->defaultStep = whole.defaultStep;
    piece->sourceCells = whole.sourceCells;
    piece->autoCpu = whole.autoCpu, piece->autoGpu = whole.autoGpu;
    out.piece = std::move(piece);
    // The cells of the whole tree's leaves below the rank's node (with their duplicates).
    std::vector<std::uint32_t> stack{d.node[rank]};
    while (!stack.empty()) {
        const KdNode node = whole.kd.nodes[stack.back()];
        stack.pop_back();
        if (node.isLeaf())
            out.ownedCells += whole.kd.partitions[node.child()].cellCount;
        else
            stack.push_back(node.child()), stack.push_back(node.child() + 1);
    }
    return out;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/dist/decompose.h"

#include <omp.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <parallel/algorithm>
#include <string>

#include "uvr/core/error.h"
#include "uvr/core/runs.h"
#include "uvr/mesh/cell_types.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/prepare/render_method.h"

namespace uvr {

std::pair<std::uint64_t, std::uint64_t> rankRun(std::uint64_t parts, int rank, int ranks) {
    UVR_CHECK(ranks >= 1 && rank >= 0 && rank < ranks, "run " << rank << " of " << ranks);
    return {parts * std::uint64_t(rank) / std::uint64_t(ranks),
            parts * std::uint64_t(rank + 1) / std::uint64_t(ranks)};
}

std::pair<std::uint64_t, std::uint64_t> rankRunOfStep(const MeshSeries& series, std::size_t step,
                                                      const Communicator& comm) {
    const std::uint64_t parts = series.partCount(step), ranks = std::uint64_t(comm.size());
    if (parts < ranks)
        throwError(ErrorKind::Unsupported, series.stepSource(step),
                   "time step " + std::to_string(step) + " is stored in " + std::to_string(parts) +
                       " parts, fewer than the " + std::to_string(ranks) +
                       " ranks that read the series' steps by parts");
    return rankRun(parts, comm.rank(), comm.size());
}

MeshShare shareOfMesh(const MeshView& mesh, const ScalarField& field, int rank, int ranks) {
    const auto [first, end] = rankRun(mesh.cellCount(), rank, ranks);
    MeshPart part = meshPart(mesh, first, end);
    MeshShare s;
    s.field.name = field.name;
    s.field.association = field.association;
    s.field.choice = field.choice;
    const std::vector<std::uint64_t>& ids =
        field.association == Association::Point ? part.pointIds : part.cellIds;
    s.field.values.reserve(ids.size());
    for (std::uint64_t i : ids) s.field.values.push_back(field.values[i]);
    s.mesh = std::move(part.mesh);
    s.pointIds = std::move(part.pointIds);
    s.cellIds = std::move(part.cellIds);
    return s;
}

std::pair<float, float> reduceFiniteRange(Communicator& comm, std::span<const float> values) {
    double r[2] = {INFINITY, INFINITY};  // min, -max
    for (float v : values)
        if (std::isfinite(v)) r[0] = std::min(r[0], double(v)), r[1] = std::min(r[1], -double(v));
    comm.allReduce(std::span<double>(r, 2), ReduceOp::Min);
    if (!(r[0] <= -r[1])) return {0.f, 0.f};
    return {float(r[0]), float(-r[1])};
}

std::vector<FieldInfo> reducedFieldInfos(Communicator& comm, const Mesh& part) {
    // Which fields hold one value over the whole mesh (NaN left out): their finite ranges
    // reduced over the ranks, in one reduction.
    std::vector<FieldInfo> infos = fieldInfos(part);
    std::vector<double> range(2 * infos.size(), INFINITY);
    for (std::size_t f = 0; f < infos.size(); ++f)
        for (float v : part.fields[f].values)
            if (std::isfinite(v))
                range[2 * f] = std::min(range[2 * f], double(v)),
                          range[2 * f + 1] = std::min(range[2 * f + 1], -double(v));
    comm.allReduce(range, ReduceOp::Min);
    for (std::size_t f = 0; f < infos.size(); ++f)
        infos[f].constant = !(range[2 * f] < -range[2 * f + 1]);
    return infos;
}

MeshShare shareOfPart(Communicator& comm, MeshPart part, const FieldSpec& spec, bool keepFields) {
    FieldChoice choice = resolveField(reducedFieldInfos(comm, part.mesh), spec);
    FieldSpec pinned = spec;
    pinned.name = part.mesh.fields[choice.index].name;
    pinned.association = part.mesh.fields[choice.index].association;
    MeshShare share;
    share.field = selectScalarField(part.mesh, pinned);
    share.field.choice = std::move(choice.choice);
    share.mesh = std::move(part.mesh);
    if (!keepFields) share.mesh.fields.clear();
    share.pointIds = std::move(part.pointIds);
    share.cellIds = std::move(part.cellIds);
    return share;
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

Bounds3f reduceBounds(Communicator& comm, const Bounds3f& b) {
    double v[6];
    for (int a = 0; a < 3; ++a) v[a] = b.lo[a], v[3 + a] = -double(b.hi[a]);
    comm.allReduce(v, ReduceOp::Min);
    Bounds3f out;
    for (int a = 0; a < 3; ++a)
        out.lo[a] = static_cast<float>(v[a]), out.hi[a] = static_cast<float>(-v[3 + a]);
    return out;
}

namespace {

/// Runs body(first, end, run) over [0, n) cut into one contiguous run per thread (OpenMP's),
/// run k holding [k n / runs, (k + 1) n / runs), and returns the run count. What each run appends
/// to lists of its own, joined in run order (joinRuns), is what one loop over [0, n) appends.
template <class Body>
int inRuns(std::size_t n, Body&& body) {
    const int runs =
        static_cast<int>(std::clamp<std::size_t>(n / 4096, 1, std::size_t(omp_get_max_threads())));
#pragma omp parallel for schedule(static, 1) num_threads(runs)
    for (int k = 0; k < runs; ++k)
        body(n * std::size_t(k) / std::size_t(runs), n * std::size_t(k + 1) / std::size_t(runs), k);
    return runs;
}

/// The runs' lists of each rank joined in run order: out[r] = runs[0][r], runs[1][r], ...
std::vector<std::vector<std::uint32_t>> joinRuns(
    std::vector<std::vector<std::vector<std::uint32_t>>>& runs, int ranks) {
    std::vector<std::vector<std::uint32_t>> out(ranks);
    for (int r = 0; r < ranks; ++r) {
        std::size_t total = 0;
        for (const auto& run : runs) total += run[r].size();
        out[r].reserve(total);
        for (auto& run : runs) {
            out[r].insert(out[r].end(), run[r].begin(), run[r].end());
            run[r] = {};
        }
    }
    return out;
}

/// The volume of a box (0 when empty).
double volumeOf(const Bounds3f& b) {
    if (b.empty()) return 0.0;
    const Vec3f e = b.extent();
    return double(e.x) * e.y * e.z;
}

/// A node of the top of the whole tree as the ranks build it: its region and depth, this rank's
/// cells of it, and the whole node's count and occupied region.
struct TopNode {
    Bounds3f region;
    int depth = 0;
    std::vector<std::uint32_t> cells;  ///< this rank's share cells (TetMesh ids) in the node
    std::uint64_t count = 0;           ///< the node's cells over every rank
    Bounds3f shrunk;                   ///< its region shrunk to its cells' bounds
    double cost = 0.0;
    bool leaf = false;  ///< a partition of the whole tree (the build splits it no further)
    int below = -1, above = -1;
    int axis = 0;
    float split = 0.f;
};

/// The node's count and occupied region over every rank.
void describeNode(Communicator& comm, TopNode& node, const std::vector<Bounds3f>& boxes) {
    std::uint64_t count = node.cells.size();
    comm.allReduce(std::span<std::uint64_t>(&count, 1), ReduceOp::Sum);
    Bounds3f cellBounds;
    for (std::uint32_t c : node.cells) cellBounds.extend(boxes[c]);
    node.count = count;
    node.shrunk = kdsplit::shrunkRegion(node.region, reduceBounds(comm, cellBounds));
}

/// The k-th smallest key over every rank's keys (0-based): radix selection, one 8-bit digit a
/// pass from the most significant, each pass's histogram summed over the ranks.
std::uint32_t kthKey(Communicator& comm, const std::vector<std::uint32_t>& keys, std::uint64_t k) {
    std::uint32_t prefix = 0, mask = 0;
    for (int shift = 24; shift >= 0; shift -= 8) {
        std::vector<std::uint64_t> hist(256, 0);
        for (std::uint32_t key : keys)
            if ((key & mask) == prefix) ++hist[(key >> shift) & 0xffu];
        comm.allReduce(hist, ReduceOp::Sum);
        std::uint32_t digit = 0;
        while (digit < 255 && k >= hist[digit]) k -= hist[digit++];
        prefix |= digit << shift;
        mask |= 0xffu << shift;
    }
    return prefix;
}

/// Splits `node` as the single-process build would (kd_partitions.cpp: splitLarge,
/// buildSubtree): false when the build makes it a partition.
bool splitNode(Communicator& comm, std::vector<TopNode>& nodes, int index,
               const std::vector<Bounds3f>& boxes, const std::vector<Vec3f>& centres,
               const KdBuildOptions& kd) {
    TopNode& node = nodes[index];
    if (!kdsplit::wantsSplit(node.count, node.depth, node.shrunk, kd.leafCells, kd.maxDepth))
        return false;
    const int axis = node.shrunk.longestAxis();
    std::vector<std::uint32_t> keys(node.cells.size());
    for (std::size_t i = 0; i < node.cells.size(); ++i)
        keys[i] = kdsplit::floatKey(centres[node.cells[i]][axis]);
    const float plane = kdsplit::keyFloat(kthKey(comm, keys, node.count / 2));
    std::vector<std::uint32_t> left, right;
    for (std::uint32_t c : node.cells) {
        if (kdsplit::goesBelow(boxes[c], axis, plane)) left.push_back(c);
        if (kdsplit::goesAbove(boxes[c], axis, plane)) right.push_back(c);
    }
    std::uint64_t sides[2] = {left.size(), right.size()};
    comm.allReduce(sides, ReduceOp::Sum);
    if (!kdsplit::keepsSplit(node.region, axis, plane, sides[0], sides[1], node.count))
        return false;
    TopNode below, above;
    below.region = above.region = node.region;
    below.region.hi[axis] = plane;
    above.region.lo[axis] = plane;
    below.depth = above.depth = node.depth + 1;
    below.cells = std::move(left);
    above.cells = std::move(right);
    node.cells = {};
    node.axis = axis;
    node.split = plane;
    node.below = static_cast<int>(nodes.size());
    node.above = node.below + 1;
    nodes.push_back(std::move(below));  // `node` is not used past here
    nodes.push_back(std::move(above));
    describeNode(comm, nodes[nodes.size() - 2], boxes);
    describeNode(comm, nodes.back(), boxes);
    return true;
}

/// Reads a trivially copyable value at `at`, moving past it.
template <class T>
T take(const std::vector<std::byte>& in, std::size_t& at) {
    UVR_CHECK(at + sizeof(T) <= in.size(), "cell message ends early");
    T v;
    std::memcpy(&v, in.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
}

/// A point as the cells carry it: its id in the whole mesh, position and value.
struct CarriedPoint {
    std::uint64_t id;
    Vec3f p;
    float value;
};

/// Reads `count` values at `at` into v, moving past them.
template <class T>
void takeAll(const std::vector<std::byte>& in, std::size_t& at, std::uint64_t count,
             std::vector<T>& v, int from) {
    UVR_CHECK(count <= (in.size() - std::min(at, in.size())) / sizeof(T),
              "the cells rank " << from << " sent end early");
    v.resize(count);
    if (count) std::memcpy(v.data(), in.data() + at, count * sizeof(T));
    at += count * sizeof(T);
}

/// One rank's cells for another (distributeMesh's step 4), as flat arrays: their points once
/// each, in the order of their first corner, and per cell its id in the whole mesh, type, corner
/// count, corners as indices into those points, and its value for cell data.
struct CellMessage {
    std::vector<CarriedPoint> points;
    std::vector<std::uint64_t> cellIds;
    std::vector<std::uint8_t> types, counts;
    std::vector<std::uint32_t> corners;
    std::vector<float> values;  ///< cell data only

    std::vector<std::byte> pack() const {
        std::vector<std::byte> out;
        out.reserve(3 * sizeof(std::uint64_t) + points.size() * sizeof(CarriedPoint) +
                    cellIds.size() * (sizeof(std::uint64_t) + 2 + sizeof(float)) +
                    corners.size() * sizeof(std::uint32_t));
        const std::uint64_t header[3] = {points.size(), cellIds.size(), corners.size()};
        appendBytes(out, header, 3);
        appendBytes(out, points.data(), points.size());
        appendBytes(out, cellIds.data(), cellIds.size());
        appendBytes(out, types.data(), types.size());
        appendBytes(out, counts.data(), counts.size());
        appendBytes(out, corners.data(), corners.size());
        appendBytes(out, values.data(), values.size());
        return out;
    }

    /// The message rank `from` packed; throws where it is malformed.
    static CellMessage unpack(const std::vector<std::byte>& in, bool cellData, int from) {
        CellMessage m;
        std::size_t at = 0;
        const auto points = take<std::uint64_t>(in, at);
        const auto cells = take<std::uint64_t>(in, at);
        const auto corners = take<std::uint64_t>(in, at);
        takeAll(in, at, points, m.points, from);
        takeAll(in, at, cells, m.cellIds, from);
        takeAll(in, at, cells, m.types, from);
        takeAll(in, at, cells, m.counts, from);
        takeAll(in, at, corners, m.corners, from);
        if (cellData) takeAll(in, at, cells, m.values, from);
        UVR_CHECK(at == in.size(), "the cells rank " << from << " sent have bytes left over");
        std::uint64_t total = 0;
        for (std::uint64_t k = 0; k < cells; ++k) {
            UVR_CHECK(m.counts[k] == cornerCount(static_cast<CellType>(m.types[k])),
                      "a cell rank " << from << " sent has " << int(m.counts[k]) << " corners");
            total += m.counts[k];
        }
        UVR_CHECK(total == corners, "the cells rank " << from << " sent miscount their corners");
        for (std::uint32_t c : m.corners)
            UVR_CHECK(c < points, "a cell rank " << from << " sent names a point it did not send");
        return m;
    }
};

}  // namespace

ScalarField routeValues(Communicator& comm, const ValueRoutes& routes, const ScalarField& field) {
    const int ranks = comm.size();
    const bool cells = field.association == Association::Cell;
    agreeOn(comm, [&] {
        if (!(cells ? routes.cells : routes.points))
            throwError(ErrorKind::Argument, "",
                       std::string("new ") + (cells ? "cell" : "point") + " values of field '" +
                           field.name + "': the ranks' pieces were made without " +
                           (cells ? "cell" : "point") + " fields, so none can be given");
        checkNewValueCount(field, cells ? routes.shareCells : routes.sharePoints,
                           "this rank's share");
    });
    const auto& send = cells ? routes.sendCells : routes.sendPoints;
    const auto& receive = cells ? routes.receiveCells : routes.receivePoints;
    std::vector<std::vector<std::byte>> toEach(ranks);
    for (int r = 0; r < ranks; ++r) {
        std::vector<float> values(send[r].size());
        for (std::size_t k = 0; k < values.size(); ++k) values[k] = field.values[send[r][k]];
        toEach[r].resize(values.size() * sizeof(float));
        if (!values.empty()) std::memcpy(toEach[r].data(), values.data(), toEach[r].size());
    }
    const std::vector<std::vector<std::byte>> received = comm.allToAll(toEach);
    ScalarField out;
    out.name = field.name;
    out.association = field.association;
    out.choice = field.choice;
    out.values.assign(cells ? routes.pieceCells : routes.piecePoints, 0.f);
    for (int r = 0; r < ranks; ++r) {
        UVR_CHECK(received[r].size() == receive[r].size() * sizeof(float),
                  "rank " << r << " sent " << received[r].size() << " bytes of values for "
                          << receive[r].size());
        for (std::size_t k = 0; k < receive[r].size(); ++k)
            std::memcpy(&out.values[receive[r][k]], received[r].data() + k * sizeof(float),
                        sizeof(float));
    }
    return out;
}

RankPiece distributeMesh(Communicator& comm, MeshShare share, const PrepareOptions& options,
                         float ghostSteps, float reach, const ProgressFn& progress) {
    const int ranks = comm.size(), me = comm.rank();
    const bool pointData = share.field.association == Association::Point;
    RankPiece out;
    out.field.name = share.field.name;
    out.field.association = share.field.association;
    out.field.choice = share.field.choice;
    out.shareCells = share.mesh.cellCount();
    auto since = std::chrono::steady_clock::now();
    const auto phaseDone = [&](const char* name) {
        const auto now = std::chrono::steady_clock::now();
        out.phaseSeconds.emplace_back(name, std::chrono::duration<double>(now - since).count());
        since = now;
    };
    // Step 1: the share split as one process splits it, in the whole mesh's frame (found from
    // every share's kept cells, as tetrahedralize finds it from the whole mesh's).
    if (progress)
        progress("splitting this rank's share of " + std::to_string(out.shareCells) +
                 " cells for the ranks' k-d tree");
    TetrahedralizeOptions cells = options.cells;
    cells.spatialOrder = false;  // the tree does not depend on the cells' order
    cells.sorter = nullptr;
    cells.frame = MeshFrame{};
    TetMesh tets = agreeOn(comm, [&] { return tetrahedralize(share.mesh, share.field, cells); });
    const Bounds3f fileBounds = reduceBounds(comm, tets.bounds);
    const MeshFrame frame = frameForBounds(fileBounds);
    if (!frame.identity()) {
        cells.frame = frame;
        tets = agreeOn(comm, [&] { return tetrahedralize(share.mesh, share.field, cells); });
    }
    // Step 2: what the whole mesh decides, reduced over the shares.
    auto piece = std::make_shared<MeshPiece>();
    piece->rank = me;
    piece->ranks = ranks;
    piece->frame = frame;
    piece->bounds = reduceBounds(comm, tets.bounds);
    {
        const bool any = tets.cellCount() > 0 && tets.valueMin <= tets.valueMax;
        double range[2] = {any ? double(tets.valueMin) : INFINITY,
                           any ? -double(tets.valueMax) : INFINITY};
        comm.allReduce(range, ReduceOp::Min);
        piece->valueMin = std::isfinite(range[0]) ? static_cast<float>(range[0]) : 0.f;
        piece->valueMax = std::isfinite(range[1]) ? static_cast<float>(-range[1]) : 0.f;
        double sums[4] = {tets.cellCount() ? tets.totalVolume : 0.0, double(tets.splitTetCount()),
                          cellSurfaceEstimate(tets, kAutoCpuLimits.nativeCellCost),
                          cellSurfaceEstimate(tets, kAutoGpuLimits.nativeCellCost)};
        comm.allReduce(sums, ReduceOp::Sum);
        std::uint64_t counts[2] = {tets.cellCount(), out.shareCells};
        comm.allReduce(counts, ReduceOp::Sum);
        piece->defaultStep = defaultStep(piece->bounds, sums[0], sums[1]);
        piece->sourceCells = counts[1];
        piece->meanSplitTets = counts[0] ? sums[1] / double(counts[0]) : 1.0;
        piece->autoCpu = autoMethodFor(sums[2], piece->bounds, false);
        piece->autoGpu = autoMethodFor(sums[3], piece->bounds, true);
    }
    phaseDone("distribute_split");
    // Step 3: the top of the whole tree, the costliest node split until there is one per rank.
    if (progress)
        progress("splitting the whole mesh's k-d tree among " + std::to_string(ranks) + " ranks");
    KdBuildOptions kd = options.kd;
    if (piece->meanSplitTets > 1.0)  // as kdBuildOptions sizes the whole mesh's leaves
        kd.leafCells = static_cast<std::uint32_t>(
            std::max(1.0, std::round(kd.leafCells / piece->meanSplitTets)));
    const std::size_t n = tets.cellCount();
    std::vector<Bounds3f> boxes(n);
    std::vector<Vec3f> centres(n);
    {
        const TetMeshView view = tets.view();
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < std::int64_t(n); ++t)
            boxes[t] = view.cellBounds(t), centres[t] = boxes[t].center();
    }
    tets = TetMesh();
    std::vector<TopNode> nodes(1);
    nodes[0].region = piece->bounds;
    nodes[0].cells.resize(n);
    for (std::size_t t = 0; t < n; ++t) nodes[0].cells[t] = static_cast<std::uint32_t>(t);
    describeNode(comm, nodes[0], boxes);
    const double totalCells = std::max<double>(1.0, double(nodes[0].count));
    const double totalVolume = volumeOf(nodes[0].shrunk);
    const auto costOf = [&](const TopNode& node) {
        return 0.5 * double(node.count) / totalCells +
               (totalVolume > 0.0 ? 0.5 * volumeOf(node.shrunk) / totalVolume : 0.0);
    };
    nodes[0].cost = costOf(nodes[0]);
    std::vector<int> frontier{0};  // left to right
    while (int(frontier.size()) < ranks) {
        int best = -1;
        for (int i = 0; i < int(frontier.size()); ++i) {
            const TopNode& f = nodes[frontier[i]];
            if (!f.leaf && (best < 0 || f.cost > nodes[frontier[best]].cost)) best = i;
        }
        if (best < 0) {
            std::size_t partitions = frontier.size();
            throwError(ErrorKind::Argument, "",
                       "the mesh has " + std::to_string(partitions) +
                           " k-d partitions, fewer than the " + std::to_string(ranks) +
                           " ranks: run on at most " + std::to_string(partitions) + " ranks");
        }
        const int index = frontier[best];
        if (!splitNode(comm, nodes, index, boxes, centres, kd)) {
            nodes[index].leaf = true;
            continue;
        }
        nodes[nodes[index].below].cost = costOf(nodes[nodes[index].below]);
        nodes[nodes[index].above].cost = costOf(nodes[nodes[index].above]);
        frontier[best] = nodes[index].below;
        frontier.insert(frontier.begin() + best + 1, nodes[index].above);
    }
    // The ranks' tree (the nodes above the frontier; a leaf names its rank).
    Decomposition& d = out.decomposition;
    for (int f : frontier) {
        d.regions.push_back(nodes[f].region);
        d.depths.push_back(nodes[f].depth);
        d.cost.push_back(nodes[f].cost);
    }
    {
        d.rankTree.emplace_back();
        std::vector<std::pair<int, std::uint32_t>> stack{{0, 0u}};  // top node, ours
        while (!stack.empty()) {
            const auto [from, to] = stack.back();
            stack.pop_back();
            const auto rank = std::find(frontier.begin(), frontier.end(), from);
            if (rank != frontier.end()) {
                d.rankTree[to].bits =
                    (static_cast<std::uint32_t>(rank - frontier.begin()) << 2) | 3u;
                continue;
            }
            const TopNode& t = nodes[from];
            const std::uint32_t child = static_cast<std::uint32_t>(d.rankTree.size());
            d.rankTree[to].split = t.split;
            d.rankTree[to].bits = (child << 2) | static_cast<std::uint32_t>(t.axis);
            d.rankTree.emplace_back();
            d.rankTree.emplace_back();
            stack.push_back({t.above, child + 1});
            stack.push_back({t.below, child});
        }
    }
    nodes = {};
    boxes = {};
    centres = {};
    piece->region = d.regions[me];
    piece->depth = d.depths[me];
    phaseDone("distribute_tree");
    // Step 4: each source cell to every rank whose box, widened by the ghosts, it reaches.
    if (progress) progress("moving cells to the ranks that render them");
    // A little past the farthest sample ending a piece's last segment.
    const float ghost = std::max(ghostSteps * piece->defaultStep,
                                 static_cast<float>(1.05 * double(reach) * frame.scale));
    piece->ghost = ghost;
    ValueRoutes& routes = out.routes;
    routes.sharePoints = share.mesh.points.size();
    routes.shareCells = share.mesh.cellCount();
    for (const Field& f : share.mesh.fields)
        (f.association == Association::Point ? routes.points : routes.cells) = true;
    (pointData ? routes.points : routes.cells) = true;
    if (share.mesh.fields.empty()) routes.points = routes.cells = true;  // fields unknown (a view)
    routes.sendPoints.resize(ranks), routes.sendCells.resize(ranks);
    routes.receivePoints.resize(ranks), routes.receiveCells.resize(ranks);
    // The share's points in the rendering frame, and whether each lies in a rank's widened box.
    std::vector<Vec3f> local(share.mesh.points.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < std::int64_t(local.size()); ++i) {
        double p[3];
        frame.toLocal(share.mesh.points[i], p);
        local[i] = Vec3f(float(p[0]), float(p[1]), float(p[2]));
    }
    const auto inWidened = [&](Vec3f p, int r) {
        for (int a = 0; a < 3; ++a)
            if (!(p[a] >= d.regions[r].lo[a] - ghost && p[a] <= d.regions[r].hi[a] + ghost))
                return false;
        return true;
    };
    // Which ranks each cell reaches (its bounds against each widened box).
    const std::size_t shareCells = share.mesh.cellCount();
    std::vector<std::vector<std::vector<std::uint32_t>>> runs(
        omp_get_max_threads(), std::vector<std::vector<std::uint32_t>>(ranks));
    runs.resize(inRuns(shareCells, [&](std::size_t first, std::size_t end, int run) {
        std::vector<std::vector<std::uint32_t>>& lists = runs[run];
        for (std::size_t c = first; c < end; ++c) {
            Bounds3f box;
            for (std::uint32_t id : share.mesh.cell(c)) box.extend(local[id]);
            for (int r = 0; r < ranks; ++r) {
                bool reaches = !box.empty();
                for (int a = 0; a < 3; ++a)
                    reaches = reaches && box.lo[a] <= d.regions[r].hi[a] + ghost &&
                              box.hi[a] >= d.regions[r].lo[a] - ghost;
                if (reaches) lists[r].push_back(static_cast<std::uint32_t>(c));
            }
        }
    }));
    std::vector<std::vector<std::uint32_t>> reaching = joinRuns(runs, ranks);
    // A smooth normal at a point is the mean over every cell around it, so a piece also takes
    // the cells around the points its cells have outside its widened box (whichever rank's
    // share holds them): the ranks' lists of such points (global ids), one all-gather.
    {
        std::vector<std::uint64_t> outside;  // per rank r: a count, then r's ids
        for (int r = 0; r < ranks; ++r) {
            std::vector<std::vector<std::uint64_t>> idRuns(omp_get_max_threads());
            idRuns.resize(
                inRuns(reaching[r].size(), [&](std::size_t first, std::size_t end, int run) {
                    for (std::size_t k = first; k < end; ++k)
                        for (std::uint32_t id : share.mesh.cell(reaching[r][k]))
                            if (!inWidened(local[id], r)) idRuns[run].push_back(share.pointIds[id]);
                }));
            std::vector<std::uint64_t> ids;
            for (const std::vector<std::uint64_t>& run : idRuns)
                ids.insert(ids.end(), run.begin(), run.end());
            std::sort(ids.begin(), ids.end());
            ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
            outside.push_back(ids.size());
            outside.insert(outside.end(), ids.begin(), ids.end());
        }
        const std::vector<std::vector<std::uint64_t>> all = comm.allGatherValues(outside);
        outside = {};
        // Every rank's points outside rank r's box, sorted; and which of this share's points
        // lie in any such list (one pass over the cells then finds the few cells to check).
        std::vector<std::vector<std::uint64_t>> rings(ranks);
        std::vector<std::uint8_t> inRing(share.pointIds.size(), 0);
        for (int r = 0; r < ranks; ++r) {
            for (const std::vector<std::uint64_t>& from : all) {
                std::size_t at = 0;
                for (int k = 0; k < r; ++k) at += 1 + from.at(at);
                const std::uint64_t count = from.at(at);
                rings[r].insert(rings[r].end(), from.begin() + at + 1,
                                from.begin() + at + 1 + count);
            }
            std::sort(rings[r].begin(), rings[r].end());
            for (std::uint64_t id : rings[r]) {  // share.pointIds is increasing
                const auto it = std::lower_bound(share.pointIds.begin(), share.pointIds.end(), id);
                if (it != share.pointIds.end() && *it == id)
                    inRing[it - share.pointIds.begin()] = 1;
            }
        }
        // This share's cells around those points, for each rank whose widened box they miss.
        runs.assign(omp_get_max_threads(), std::vector<std::vector<std::uint32_t>>(ranks));
        runs.resize(inRuns(shareCells, [&](std::size_t first, std::size_t end, int run) {
            for (std::size_t c = first; c < end; ++c) {
                const std::span<const std::uint32_t> corners = share.mesh.cell(c);
                if (std::none_of(corners.begin(), corners.end(),
                                 [&](std::uint32_t id) { return inRing[id] != 0; }))
                    continue;
                const auto cell = static_cast<std::uint32_t>(c);
                for (int r = 0; r < ranks; ++r)
                    if (!std::binary_search(reaching[r].begin(), reaching[r].end(), cell) &&
                        std::any_of(corners.begin(), corners.end(), [&](std::uint32_t id) {
                            return inRing[id] &&
                                   std::binary_search(rings[r].begin(), rings[r].end(),
                                                      share.pointIds[id]);
                        }))
                        runs[run][r].push_back(cell);
            }
        }));
        const std::vector<std::vector<std::uint32_t>> more = joinRuns(runs, ranks);
        runs = {};
        for (int r = 0; r < ranks; ++r) {
            if (more[r].empty()) continue;
            std::vector<std::uint32_t> merged;
            std::merge(reaching[r].begin(), reaching[r].end(), more[r].begin(), more[r].end(),
                       std::back_inserter(merged));
            reaching[r] = std::move(merged);
        }
    }
    local = {};
    phaseDone("distribute_reach");
    // The messages: per rank, its cells' points once each and the cells as indices into them.
    std::vector<std::vector<std::byte>> toEach(ranks);
    CellMessage own;  // this rank's cells for itself: kept as they are, not packed
    {
        std::vector<int> sentTo(share.mesh.points.size(), -1);
        std::vector<std::uint32_t> slot(share.mesh.points.size());
        for (int r = 0; r < ranks; ++r) {
            CellMessage m;
            std::vector<std::uint32_t>& points = routes.sendPoints[r];
            m.cellIds.reserve(reaching[r].size());
            for (std::uint32_t c : reaching[r]) {
                const std::span<const std::uint32_t> corners = share.mesh.cell(c);
                routes.sendCells[r].push_back(c);
                m.cellIds.push_back(share.cellIds[c]);
                m.types.push_back(static_cast<std::uint8_t>(share.mesh.cellTypes[c]));
                m.counts.push_back(static_cast<std::uint8_t>(corners.size()));
                for (std::uint32_t id : corners) {
                    if (sentTo[id] != r) {
                        sentTo[id] = r, slot[id] = static_cast<std::uint32_t>(points.size());
                        points.push_back(id);
                        m.points.push_back({share.pointIds[id], share.mesh.points[id],
                                            pointData ? share.field.values[id] : 0.f});
                    }
                    m.corners.push_back(slot[id]);
                }
                if (!pointData) m.values.push_back(share.field.values[c]);
            }
            reaching[r] = {};
            if (r == me)
                own = std::move(m);
            else
                toEach[r] = m.pack();
        }
    }
    if (!routes.points) routes.sendPoints.assign(ranks, {});
    if (!routes.cells) routes.sendCells.assign(ranks, {});
    share = MeshShare();
    std::vector<std::vector<std::byte>> received = comm.allToAll(toEach);
    toEach = {};
    phaseDone("distribute_exchange");
    // Step 5: the piece: its points in the whole mesh's order, its cells in the whole mesh's.
    std::vector<CellMessage> got(ranks);
    std::vector<std::uint64_t> pointStart(ranks + 1, 0), cellStart(ranks + 1, 0);
    for (int from = 0; from < ranks; ++from) {
        got[from] =
            from == me ? std::move(own) : CellMessage::unpack(received[from], !pointData, from);
        received[from] = {};
        pointStart[from + 1] = pointStart[from] + got[from].points.size();
        cellStart[from + 1] = cellStart[from] + got[from].cellIds.size();
    }
    received = {};
    // Points: each id once (the senders' shares overlap on their common faces), by id.
    std::vector<std::uint32_t> pieceOf(pointStart[ranks]);
    {
        std::vector<std::pair<std::uint64_t, std::uint64_t>> byId;  // id, index over the senders
        byId.reserve(pointStart[ranks]);
        for (int from = 0; from < ranks; ++from)
            for (std::size_t k = 0; k < got[from].points.size(); ++k)
                byId.push_back({got[from].points[k].id, pointStart[from] + k});
        __gnu_parallel::sort(byId.begin(), byId.end());
        for (std::size_t i = 0; i < byId.size(); ++i) {
            if (i == 0 || byId[i].first != byId[i - 1].first) {
                const std::uint64_t g = byId[i].second;
                const int from = static_cast<int>(runOf(pointStart.data(), ranks, g));
                const CarriedPoint& p = got[from].points[g - pointStart[from]];
                out.mesh.points.push_back(p.p);
                if (pointData) out.field.values.push_back(p.value);
            }
            pieceOf[byId[i].second] = static_cast<std::uint32_t>(out.mesh.points.size() - 1);
        }
    }
    // Cells: each sender's come in increasing id order and the shares are disjoint, so their
    // merge is the whole mesh's order.
    std::vector<std::pair<std::uint64_t, std::uint64_t>> cellOrder;  // id, index over the senders
    cellOrder.reserve(cellStart[ranks]);
    bool sorted = true;
    for (int from = 0; from < ranks; ++from) {
        const auto begin = cellOrder.size();
        for (std::size_t k = 0; k < got[from].cellIds.size(); ++k)
            cellOrder.push_back({got[from].cellIds[k], cellStart[from] + k});
        sorted = sorted && std::is_sorted(cellOrder.begin() + begin, cellOrder.end());
        if (sorted)
            std::inplace_merge(cellOrder.begin(), cellOrder.begin() + begin, cellOrder.end());
    }
    if (!sorted) __gnu_parallel::sort(cellOrder.begin(), cellOrder.end());
    std::vector<std::vector<std::uint64_t>> cornerStart(ranks);  // per sender's cell
    std::uint64_t cornerTotal = 0;
    for (int from = 0; from < ranks; ++from) {
        cornerStart[from].resize(got[from].counts.size() + 1, 0);
        for (std::size_t k = 0; k < got[from].counts.size(); ++k)
            cornerStart[from][k + 1] = cornerStart[from][k] + got[from].counts[k];
        cornerTotal += cornerStart[from].back();
        if (routes.cells) routes.receiveCells[from].resize(got[from].cellIds.size());
    }
    // Each cell's corners start where the cells before it end (a prefix sum), so every cell is
    // written on its own.
    const std::size_t pieceCells = cellOrder.size();
    std::vector<int> senderOf(pieceCells);
    out.mesh.cellOffsets.assign(pieceCells + 1, 0);
#pragma omp parallel for schedule(static)
    for (std::int64_t s = 0; s < std::int64_t(pieceCells); ++s) {
        const std::uint64_t g = cellOrder[s].second;
        const int from = static_cast<int>(runOf(cellStart.data(), ranks, g));
        senderOf[s] = from;
        out.mesh.cellOffsets[s + 1] = got[from].counts[g - cellStart[from]];
    }
    for (std::size_t s = 0; s < pieceCells; ++s)
        out.mesh.cellOffsets[s + 1] += out.mesh.cellOffsets[s];
    out.mesh.cellTypes.resize(pieceCells);
    out.mesh.cellIndices.resize(cornerTotal);
    if (!pointData) out.field.values.resize(pieceCells);
#pragma omp parallel for schedule(static)
    for (std::int64_t s = 0; s < std::int64_t(pieceCells); ++s) {
        const int from = senderOf[s];
        const std::size_t k = static_cast<std::size_t>(cellOrder[s].second - cellStart[from]);
        const CellMessage& m = got[from];
        out.mesh.cellTypes[s] = static_cast<CellType>(m.types[k]);
        std::uint64_t at = out.mesh.cellOffsets[s];
        for (std::uint64_t j = cornerStart[from][k]; j < cornerStart[from][k + 1]; ++j)
            out.mesh.cellIndices[at++] = pieceOf[pointStart[from] + m.corners[j]];
        if (!pointData) out.field.values[s] = m.values[k];
        if (routes.cells) routes.receiveCells[from][k] = static_cast<std::uint32_t>(s);
    }
    // The routes' receiving ends: the senders' orders, as the piece's indices.
    routes.piecePoints = out.mesh.points.size();
    routes.pieceCells = cellOrder.size();
    if (routes.points)
        for (int from = 0; from < ranks; ++from)
            routes.receivePoints[from].assign(pieceOf.begin() + pointStart[from],
                                              pieceOf.begin() + pointStart[from + 1]);
    out.piece = std::move(piece);
    phaseDone("distribute_assemble");
    return out;
}

}  // namespace uvr

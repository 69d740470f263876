// SPDX-License-Identifier: MIT
#include "uvr/prepare/prepared_mesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <string>

#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/mesh/tet_math.h"

namespace uvr {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Runs fn on a thread of its own (with its own OpenMP team), timed: CPU work beside the GPU's.
template <class Fn>
auto beside(Fn fn) {
    return std::async(std::launch::async, [fn = std::move(fn)] {
        const auto start = std::chrono::steady_clock::now();
        auto result = fn();
        return std::make_pair(std::move(result), secondsSince(start));
    });
}

/// Runs `build`, a builder of PrepareOptions::builderDevice (the GPU's), and says whether it
/// built: false when that device ran out of memory for it (Error(Resource)), after which the
/// caller builds `phase` on the CPU. The switch is heard through `progress` and noted in
/// out.builtOnCpuInstead: the picture comes without the user choosing another build device.
template <class Build>
bool buildElsewhere(PreparedMesh& out, const char* phase, const PrepareOptions& options,
                    const ProgressFn& progress, Build&& build) {
    try {
        build();
        out.builtElsewhere = true;
        return true;
    } catch (const Error& e) {
        if (e.kind() != ErrorKind::Resource) throw;
        if (progress)
            progress(std::string(e.what()) + "; building the " + phase + " on the CPU instead of " +
                     options.builderDevice);
        out.builtOnCpuInstead.emplace_back(phase);
        return false;
    }
}

/// Meshes of up to this many cells get cell-tree leaves of at most kCpuCellTreeLeaf whatever
/// PrepareOptions::cellTreeLeaf asks (the GPU's kCellTreeLeaf): on small non-convex meshes
/// searches are not rare (SPX: one sample in five on an H200; disk_out_ref.ex2: one in seven),
/// and 32-cell leaves made the GPU's adaptive frame 1.4-5.4x slower there (SPX 40.8 -> 7.6 ms,
/// Oxygen Post 15.4 -> 5.6 ms; docs/PERFORMANCE.md, "The default method"). 2-cell leaves cost
/// 32 bytes per cell against 2: at most 512 MiB here.
constexpr std::uint64_t kSmallCellTreeCells = std::uint64_t(1) << 24;

}  // namespace

KdBuildOptions kdBuildOptions(const TetMesh& tets, const PrepareOptions& options) {
    KdBuildOptions kd = options.kd;
    // The leaf size counts tetrahedra of the split: native cells fill a leaf as the tetrahedra
    // they stand for would (partitions of the same size in space).
    if (tets.meanSplitTets() > 1.0)
        kd.leafCells = static_cast<std::uint32_t>(
            std::max(1.0, std::round(kd.leafCells / tets.meanSplitTets())));
    return kd;
}

PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field,
                         const PrepareOptions& options, const ProgressFn& progress) {
    PreparedMesh out;
    out.sourceCells = mesh.cellCount();
    auto start = std::chrono::steady_clock::now();
    if (progress)
        progress(options.cells.splitCells
                     ? "splitting " + std::to_string(mesh.cellCount()) + " cells into tetrahedra"
                     : "preparing " + std::to_string(mesh.cellCount()) + " cells");
    TetrahedralizeOptions cells = options.cells;
    if (options.piece) cells.frame = options.piece->frame;
    // The builders (the GPU's) only where the mesh is large enough to pay.
    const bool large = mesh.cellCount() >= options.builderMinTets;
    if (!large) cells.sorter = nullptr;
    // For the face neighbours found elsewhere, the points' welded ids (coincidentPointIds) on a
    // thread of their own beside the split, which keeps the points' numbering.
    std::future<std::pair<std::vector<std::uint32_t>, double>> welding;
    if (large && options.faceMatcher)
        welding = beside([points = mesh.points] { return coincidentPointIds(points); });
    if (!(cells.sorter && buildElsewhere(out, "split", options, progress, [&] {
              out.tets = tetrahedralize(mesh, field, cells, progress.fraction);
          }))) {
        cells.sorter = nullptr;
        out.tets = tetrahedralize(mesh, field, cells, progress.fraction);
    }
    if (options.piece) out.tets.wholeMeanSplitTets = options.piece->meanSplitTets;
    std::vector<std::uint32_t> welded;
    if (welding.valid()) welded = std::move(welding.get().first);  // before the points are freed
    if (options.afterSplit) options.afterSplit();
    out.piece = options.piece;
    out.autoChoice = !options.piece      ? autoMethod(out.tets, options.autoOnGpu)
                     : options.autoOnGpu ? options.piece->autoGpu
                                         : options.piece->autoCpu;
    out.splitSeconds = secondsSince(start);
    out.phaseSeconds.emplace_back("split", out.splitSeconds);
    // What RenderMethod::Auto renders with, besides what was asked for.
    const bool forExact = options.forAuto && out.autoChoice->method == RenderMethod::Exact;
    // Adaptive, weighed against the reference each frame (weighReference): both.
    const bool weighs = options.forAuto && out.autoChoice->adaptiveSampleCost > 0.0;
    const bool withBvh = options.meshBvh || forExact || weighs;
    const bool withPartitions = options.partitions || (options.forAuto && !forExact);
    const std::uint32_t cellTreeLeaf = out.tets.cellCount() <= kSmallCellTreeCells
                                           ? std::min(options.cellTreeLeaf, kCpuCellTreeLeaf)
                                           : options.cellTreeLeaf;

    // The other builders too, by the cells of the split.
    const bool elsewhere = out.tets.cellCount() >= options.builderMinTets;
    const LbvhBuilder lbvh = elsewhere ? options.lbvh : nullptr;
    const KdSplitter splitter = elsewhere ? options.kdSplitter : nullptr;
    const auto faceMatcher = elsewhere ? options.faceMatcher : nullptr;
    const SeedBuilder seedBuilder = elsewhere ? options.seedBuilder : nullptr;
    const MacroBuilder macroBuilder =
        elsewhere && options.macroGrids ? options.macroBuilder : nullptr;
    if (withBvh) {
        start = std::chrono::steady_clock::now();
        if (progress)
            progress("building the BVH over " + std::to_string(out.tets.cellCount()) + " cells" +
                     (lbvh ? " (LBVH on " + options.builderDevice + ")" : ""));
        if (!(lbvh && buildElsewhere(out, "bvh", options, progress,
                                     [&] { out.bvh = buildMeshLbvh(out.tets, lbvh); }))) {
            std::vector<Bounds3f> boxes;
            std::vector<Vec3f> centers;
            tetBoxesAndCenters(out.tets, boxes, centers);
            out.bvh = buildBvh(boxes, centers);
        }
        out.bvhSeconds = secondsSince(start);
        out.phaseSeconds.emplace_back("bvh", out.bvhSeconds);
    }

    // While the GPU finds the neighbours and partitions, the CPU builds the cell tree (it needs
    // only the cells) and then the neighbours' codes on threads of their own.
    std::future<std::pair<Bvh, double>> cellTree;
    if (faceMatcher && withPartitions)
        cellTree =
            beside([&tets = out.tets, leaf = cellTreeLeaf] { return buildCellTree(tets, leaf); });
    start = std::chrono::steady_clock::now();
    if (progress)
        progress(faceMatcher ? "finding face neighbours (on " + options.builderDevice +
                                   (cellTree.valid() ? "; the cell tree beside it)" : ")")
                             : std::string("finding face neighbours"));
    // On the CPU their codes take 0.74 of 4.91 seconds at 100M tetrahedra.
    constexpr double kNeighborsEnd = 4.17 / 4.91;
    std::future<std::pair<CompactNeighbors, double>> codes;
    if (faceMatcher && buildElsewhere(out, "neighbours", options, progress, [&] {
            // Welded again where the split moved the points into a frame (equal points stay
            // equal, but the weld is of the points the matcher reads), or where none were.
            if (welded.size() != out.tets.points.size() || !out.tets.frame.identity())
                welded = coincidentPointIds(out.tets.points);
            out.neighbors = faceMatcher(out.tets, welded, progress.fraction);
        })) {
        welded = {};
        codes = beside([&tets = out.tets, &neighbors = out.neighbors] {
            return compactNeighbors(tets, neighbors);
        });
    } else {
        welded = {};
        out.neighbors =
            buildTetNeighbors(out.tets, subRange(progress.fraction, 0.0, kNeighborsEnd));
        out.neighborCodes = compactNeighbors(out.tets, out.neighbors,
                                             subRange(progress.fraction, kNeighborsEnd, 1.0));
    }
    out.adjacencySeconds = secondsSince(start);
    out.phaseSeconds.emplace_back("neighbours", out.adjacencySeconds);

    if (withPartitions) {
        if (progress)
            progress("building k-d partitions (up to " + std::to_string(options.kd.leafCells) +
                     " cells each" + (splitter ? ", on " + options.builderDevice : std::string()) +
                     ")");
        KdBuildOptions kd = kdBuildOptions(out.tets, options);
        if (splitter) kd.splitter = splitter;
        if (const MeshPiece* piece = options.piece.get())
            kd.root = KdSubtreeRoot{piece->region, piece->depth, piece->bounds.diagonal()};
        start = std::chrono::steady_clock::now();
        if (!(splitter && buildElsewhere(out, "partitions", options, progress, [&] {
                  out.kd = buildKdPartitions(out.tets, kd, progress.fraction);
              }))) {
            kd.splitter = options.kd.splitter;
            out.kd = buildKdPartitions(out.tets, kd, progress.fraction);
        }
        // A piece's traversal starts at the whole mesh's bounds and narrows to its box (the
        // marchers' PieceView), as one process's does.
        if (options.piece) out.kd->bounds = options.piece->bounds;
        out.phaseSeconds.emplace_back("partitions", secondsSince(start));
        if (cellTree.valid()) {
            auto [tree, seconds] = cellTree.get();
            out.cellTree = std::move(tree);
            out.phaseSeconds.emplace_back("cell_tree", seconds);
        } else {
            if (progress) progress("building the cell tree");
            start = std::chrono::steady_clock::now();
            out.cellTree = buildCellTree(out.tets, cellTreeLeaf, progress.fraction);
            out.phaseSeconds.emplace_back("cell_tree", secondsSince(start));
        }
        if (options.seedGrids) {
            if (progress)
                progress("building seed grids" +
                         (seedBuilder ? " (on " + options.builderDevice + ")" : std::string()));
            start = std::chrono::steady_clock::now();
            if (!(seedBuilder && buildElsewhere(out, "seed_grids", options, progress, [&] {
                      out.seeds =
                          seedBuilder(out.tets, *out.kd, kTetsPerSeedCell, progress.fraction);
                  })))
                out.seeds = buildSeedGrids(out.tets, *out.kd, kTetsPerSeedCell, progress.fraction);
            out.phaseSeconds.emplace_back("seed_grids", secondsSince(start));
        }
        bool macroElsewhere = false;
        if (macroBuilder) {
            if (progress)
                progress("building macrocell grids and gradient spreads (on " +
                         options.builderDevice + ")");
            start = std::chrono::steady_clock::now();
            macroElsewhere = buildElsewhere(out, "macrocells", options, progress, [&] {
                MacroBuild built = macroBuilder(out.tets, *out.kd, out.neighbors, kTetsPerMacroCell,
                                                progress.fraction);
                out.gradientSpread = std::move(built.gradientSpread);
                out.macro = std::move(built.macro);
            });
            if (macroElsewhere) out.phaseSeconds.emplace_back("macrocells", secondsSince(start));
        }
        if (!macroElsewhere) {
            if (progress) progress("measuring the partitions' gradient spreads");
            start = std::chrono::steady_clock::now();
            out.gradientSpread = partitionGradientSpread(out.tets, *out.kd, progress.fraction);
            out.phaseSeconds.emplace_back("gradient_spreads", secondsSince(start));
        }
        if (progress) progress("looking for NaN values");
        start = std::chrono::steady_clock::now();
        out.partitionNan = partitionNanFlags(out.tets, *out.kd);
        out.phaseSeconds.emplace_back("nan_flags", secondsSince(start));
        if (options.macroGrids && !macroElsewhere) {
            if (progress) progress("building macrocell grids");
            start = std::chrono::steady_clock::now();
            out.macro = buildMacroGrids(out.tets, *out.kd, out.neighbors, kTetsPerMacroCell,
                                        progress.fraction);
            out.phaseSeconds.emplace_back("macrocells", secondsSince(start));
        }
    }
    if (codes.valid()) {
        auto [made, seconds] = codes.get();
        out.neighborCodes = std::move(made);
        out.phaseSeconds.emplace_back("neighbour_codes", seconds);
    }
    return out;
}

void checkNewValueCount(const ScalarField& field, std::uint64_t expected, const std::string& of) {
    if (field.values.size() == expected) return;
    throwError(ErrorKind::Argument, "",
               "new values of field '" + field.name + "': " + std::to_string(field.values.size()) +
                   " " + associationName(field.association) + " values, expected " +
                   std::to_string(expected) + " (one per " +
                   (field.association == Association::Cell ? "cell" : "point") + " of " + of + ")");
}

void updateFieldValues(PreparedMesh& mesh, const ScalarField& field) {
    const auto start = std::chrono::steady_clock::now();
    if (!mesh.cacheFile.empty())
        throwError(ErrorKind::Argument, mesh.cacheFile,
                   "prepared from the cache " + mesh.cacheFile +
                       ", which holds only what rendering reads: change fields (or time steps) by "
                       "preparing from the mesh");
    // Checked before anything changes (assignTetValues checks it too).
    checkNewValueCount(
        field, field.association == Association::Cell ? mesh.sourceCells : mesh.tets.points.size(),
        "the prepared mesh");
    assignTetValues(mesh.tets, field);
    // Smooth gradients follow the values once shading has asked for them.
    if (!mesh.tets.blockGradients.empty()) computeSmoothGradients(mesh.tets);
    if (mesh.kd) {
        computePartitionValueRanges(mesh.tets, *mesh.kd);
        mesh.gradientSpread = partitionGradientSpread(mesh.tets, *mesh.kd);
        mesh.partitionNan = partitionNanFlags(mesh.tets, *mesh.kd);
        if (mesh.macro) fillMacroCells(mesh.tets, *mesh.kd, mesh.neighbors, *mesh.macro);
    }
    ++mesh.valueUpdates;
    mesh.valueUpdateSeconds = secondsSince(start);
}

std::vector<std::uint8_t> partitionNanFlags(const TetMesh& tets, const KdPartitions& kd) {
    const auto isNan = [](float v) { return v != v; };
    if (std::none_of(tets.values.begin(), tets.values.end(), isNan)) return {};
    const bool cellData = tets.association == Association::Cell;
    std::vector<std::uint8_t> out(kd.partitions.size(), 0);
    const std::int64_t n = static_cast<std::int64_t>(kd.partitions.size());
    const TetMeshView view = tets.view();
#pragma omp parallel for schedule(dynamic, 16)
    for (std::int64_t p = 0; p < n; ++p) {
        const KdPartition& part = kd.partitions[p];
        bool nan = false;
        for (std::uint32_t i = 0; i < part.cellCount && !nan; ++i) {
            const std::uint32_t t = kd.cells[part.firstCell + i];
            if (cellData) {
                nan = isNan(tets.values[t]);
            } else {
                std::uint32_t ids[kMaxCellCorners];
                const int corners = view.corners(t, ids);
                for (int k = 0; k < corners; ++k) nan = nan || isNan(tets.values[ids[k]]);
            }
        }
        out[p] = nan;
    }
    return out;
}

std::vector<float> partitionGradientSpread(const TetMesh& tets, const KdPartitions& kd,
                                           const FractionFn& progress) {
    const std::int64_t n = static_cast<std::int64_t>(kd.partitions.size());
    std::vector<float> out(n, 0.f);
    ProgressCounter done(progress, n);
    if (tets.association == Association::Cell) {
        for (std::int64_t p = 0; p < n; ++p)
            if (kd.partitions[p].cellCount > 0) out[p] = INFINITY;
        done.finish();
        return out;
    }
    const TetMeshView view = tets.view();
#pragma omp parallel for schedule(dynamic, 16)
    for (std::int64_t p = 0; p < n; ++p) {
        const KdPartition& part = kd.partitions[p];
        Bounds3f box;
        for (std::uint32_t i = 0; i < part.cellCount; ++i)
            box.extend(cellGradientBounds(view, kd.cells[part.firstCell + i]));
        out[p] = box.empty() ? 0.f : length(box.hi - box.lo);
        done.add();
    }
    done.finish();
    return out;
}

PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field) {
    const PrepareOptions defaults;
    return prepareMesh(mesh, field, defaults);
}

float PreparedMesh::wholeDefaultStep() const {
    return piece ? piece->defaultStep : defaultStep(tets);
}

float defaultStep(const TetMesh& mesh) {
    return defaultStep(mesh.bounds, mesh.cellCount() ? mesh.totalVolume : 0.0,
                       double(mesh.splitTetCount()));
}

float defaultStep(const Bounds3f& bounds, double totalVolume, double splitTets) {
    const double diagonal = bounds.diagonal();
    if (!(splitTets > 0.0) || !(totalVolume > 0.0))
        return diagonal > 0.0 ? static_cast<float>(0.01 * diagonal) : 1.f;
    const double mean = 0.5 * std::cbrt(totalVolume / splitTets);
    const double step = std::min(mean, diagonal / kMinSamplesPerDiagonal);
    return static_cast<float>(std::max(step, kMinDefaultStepFraction * diagonal));
}

float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount) {
    const double d = bounds.diagonal();
    if (cellCount == 0 || !(d > 0.0)) return 1.f;
    return static_cast<float>(d / std::cbrt(double(cellCount)));
}

std::vector<RenderMethod> renderableMethods(const PreparedMesh& mesh) {
    const bool kd = mesh.kd.has_value();
    const bool bvh = !mesh.bvh.nodes.empty() || mesh.tets.cellCount() == 0;
    std::vector<RenderMethod> out;
    for (const MethodName& m : kMethods) {
        const bool ok = m.method == RenderMethod::Auto         ? kd || bvh
                        : m.method == RenderMethod::Partitions ? kd
                                                               : bvh;
        if (ok) out.push_back(m.method);
    }
    return out;
}

std::vector<float> preparedValues(const PreparedMesh& mesh) {
    const TetMesh& t = mesh.tets;
    if (!t.values.empty()) return t.values;
    std::vector<float> out;
    out.reserve(t.blockVertices.size());
    for (const BlockVertex& v : t.blockVertices) out.push_back(v.value);
    return out;
}

}  // namespace uvr

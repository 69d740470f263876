// SPDX-License-Identifier: MIT
#include "uvr/render/render_setup.h"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <string>

#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/render/settings_vocabulary.h"
#include "uvr/tf/tf_table.h"

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

/// Meshes of up to this many cells get cell-tree leaves of at most kCpuCellTreeLeaf whatever
/// PrepareOptions::cellTreeLeaf asks (the GPU's kCellTreeLeaf): on small non-convex meshes
/// searches are not rare (SPX: one sample in five on an H200; disk_out_ref.ex2: one in seven),
/// and 32-cell leaves made the GPU's adaptive frame 1.4-5.4x slower there (SPX 40.8 -> 7.6 ms,
/// Oxygen Post 15.4 -> 5.6 ms; docs/PERFORMANCE.md, "The default method"). 2-cell leaves cost
/// 32 bytes per cell against 2: at most 512 MiB here.
constexpr std::uint64_t kSmallCellTreeCells = std::uint64_t(1) << 24;

}  // namespace

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
    // The builders (the GPU's) only where the mesh is large enough to pay.
    const bool large = mesh.cellCount() >= options.builderMinTets;
    if (!large) cells.sorter = nullptr;
    // For the face neighbours found elsewhere, the points' welded ids (coincidentPointIds) on a
    // thread of their own beside the split, which keeps the points' numbering.
    std::future<std::pair<std::vector<std::uint32_t>, double>> welding;
    if (large && options.faceMatcher)
        welding = beside([points = mesh.points] { return coincidentPointIds(points); });
    out.tets = tetrahedralize(mesh, field, cells, progress.fraction);
    std::vector<std::uint32_t> welded;
    if (welding.valid()) welded = std::move(welding.get().first);  // before the points are freed
    if (options.afterSplit) options.afterSplit();
    out.autoChoice = autoMethod(out.tets, options.autoOnGpu);
    out.splitSeconds = secondsSince(start);
    out.phaseSeconds.emplace_back("split", out.splitSeconds);
    // What RenderMethod::Auto renders with, besides what was asked for.
    const bool forExact = options.forAuto && out.autoChoice->method == RenderMethod::Exact;
    const bool withBvh = options.meshBvh || forExact;
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
    out.builtElsewhere =
        elsewhere && (lbvh || splitter || faceMatcher || seedBuilder || macroBuilder);
    if (withBvh) {
        start = std::chrono::steady_clock::now();
        if (progress)
            progress("building the BVH over " + std::to_string(out.tets.cellCount()) + " cells" +
                     (lbvh ? " (LBVH on " + options.builderDevice + ")" : ""));
        if (lbvh) {
            out.bvh = buildMeshLbvh(out.tets, lbvh);
        } else {
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
    if (faceMatcher) {
        // Welded again where the split moved the points into a frame (equal points stay equal,
        // but the weld is of the points the matcher reads), or where none were welded.
        if (welded.size() != out.tets.points.size() || !out.tets.frame.identity())
            welded = coincidentPointIds(out.tets.points);
        out.neighbors = faceMatcher(out.tets, welded, progress.fraction);
        welded = {};
        codes = beside([&tets = out.tets, &neighbors = out.neighbors] {
            return compactNeighbors(tets, neighbors);
        });
    } else {
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
        KdBuildOptions kd = options.kd;
        // The leaf size counts tetrahedra of the split: native cells fill a leaf as the
        // tetrahedra they stand for would (partitions of the same size in space).
        if (out.tets.hasNative())
            kd.leafCells = static_cast<std::uint32_t>(
                std::max(1.0, std::round(kd.leafCells / out.tets.meanSplitTets())));
        if (splitter) kd.splitter = splitter;
        start = std::chrono::steady_clock::now();
        out.kd = buildKdPartitions(out.tets, kd, progress.fraction);
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
            out.seeds =
                seedBuilder
                    ? seedBuilder(out.tets, *out.kd, kTetsPerSeedCell, progress.fraction)
                    : buildSeedGrids(out.tets, *out.kd, kTetsPerSeedCell, progress.fraction);
            out.phaseSeconds.emplace_back("seed_grids", secondsSince(start));
        }
        if (macroBuilder) {
            if (progress)
                progress("building macrocell grids and gradient spreads (on " +
                         options.builderDevice + ")");
            start = std::chrono::steady_clock::now();
            MacroBuild built = macroBuilder(out.tets, *out.kd, out.neighbors, kTetsPerMacroCell,
                                            progress.fraction);
            out.gradientSpread = std::move(built.gradientSpread);
            out.macro = std::move(built.macro);
            out.phaseSeconds.emplace_back("macrocells", secondsSince(start));
        } else {
            if (progress) progress("measuring the partitions' gradient spreads");
            start = std::chrono::steady_clock::now();
            out.gradientSpread = partitionGradientSpread(out.tets, *out.kd, progress.fraction);
            out.phaseSeconds.emplace_back("gradient_spreads", secondsSince(start));
        }
        if (progress) progress("looking for NaN values");
        start = std::chrono::steady_clock::now();
        out.partitionNan = partitionNanFlags(out.tets, *out.kd);
        out.phaseSeconds.emplace_back("nan_flags", secondsSince(start));
        if (options.macroGrids && !macroBuilder) {
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

void updateFieldValues(PreparedMesh& mesh, const ScalarField& field) {
    const auto start = std::chrono::steady_clock::now();
    if (!mesh.cacheFile.empty())
        throwError(ErrorKind::Argument, mesh.cacheFile,
                   "prepared from the cache " + mesh.cacheFile +
                       ", which holds only what rendering reads: change fields (or time steps) by "
                       "preparing from the mesh");
    // Checked before anything changes (assignTetValues checks it too).
    const bool cellData = field.association == Association::Cell;
    const std::uint64_t expected = cellData ? mesh.sourceCells : mesh.tets.points.size();
    if (field.values.size() != expected)
        throwError(ErrorKind::Argument, "",
                   "new values of field '" + field.name +
                       "': " + std::to_string(field.values.size()) + " " +
                       associationName(field.association) + " values, expected " +
                       std::to_string(expected) + " (one per " + (cellData ? "cell" : "point") +
                       " of the prepared mesh)");
    assignTetValues(mesh.tets, field);
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

float toleranceForQuality(float quality) {
    checkSetting(settingNamed("quality"), quality);  // SettingError out of range
    return kToleranceScale * (1.f - quality);
}

PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field) {
    const PrepareOptions defaults;
    return prepareMesh(mesh, field, defaults);
}

float defaultStep(const TetMesh& mesh) {
    const double diagonal = mesh.bounds.diagonal();
    if (mesh.cellCount() == 0 || !(mesh.totalVolume > 0.0))
        return diagonal > 0.0 ? static_cast<float>(0.01 * diagonal) : 1.f;
    const double mean = 0.5 * std::cbrt(mesh.totalVolume / double(mesh.splitTetCount()));
    const double step = std::min(mean, diagonal / kMinSamplesPerDiagonal);
    return static_cast<float>(std::max(step, kMinDefaultStepFraction * diagonal));
}

float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount) {
    const double d = bounds.diagonal();
    if (cellCount == 0 || !(d > 0.0)) return 1.f;
    return static_cast<float>(d / std::cbrt(double(cellCount)));
}

namespace {

/// A field value for a message (6 significant digits).
std::string fmtValue(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

/// Refuses a log-scale mapping over a range with no positive value (`given`: the range is the
/// `range` setting, else the field's).
[[noreturn]] void refuseLogRange(bool given, double lo, double hi) {
    const std::string range = "[" + fmtValue(lo) + ", " + fmtValue(hi) + "]";
    throwError(ErrorKind::Argument, "",
               "`log` needs positive values: " +
                   (given ? "`range` " + range : "the field's range " + range) +
                   " has none; give `range` LO,HI with 0 < LO <= HI");
}

}  // namespace

bool tunesAdaptive(const RenderSettings& s) {
    const RenderSettings d;
    for (const SettingDef& def : settingsVocabulary())
        if (def.tunesAdaptive && def.get(s) != def.get(d)) return true;
    return false;
}

ResolvedMethod resolveMethod(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu) {
    if (settings.method != RenderMethod::Auto) return {settings.method, ""};
    if (tunesAdaptive(settings))
        return {RenderMethod::Partitions, "auto: adaptive (the settings tune its sampling)"};
    const AutoMethodChoice choice = mesh.autoChoice && mesh.autoChoice->gpu == gpu
                                        ? *mesh.autoChoice
                                        : autoMethod(mesh.tets, gpu);
    const bool bvh = !mesh.bvh.nodes.empty(), kd = mesh.kd.has_value();
    if (choice.method == RenderMethod::Exact && !bvh && kd)
        return {RenderMethod::Partitions,
                choice.reason() + "; adaptive: the mesh BVH exact needs was not prepared"};
    if (choice.method == RenderMethod::Partitions && !kd && bvh)
        return {RenderMethod::Exact,
                choice.reason() + "; exact: the partitions adaptive needs were not prepared"};
    return {choice.method, choice.reason()};
}

const char* stepRuleName(StepRule rule) {
    return rule == StepRule::Variance ? "variance" : "error";
}

const char* samplingName(bool preintegrated) {
    return preintegrated ? "preintegrated" : "point";
}

void validateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& msg) { throwError(ErrorKind::Argument, "", msg); };
    constexpr int kMaxSide = 16384;
    if (s.width < 1 || s.height < 1 || s.width > kMaxSide || s.height > kMaxSide)
        throw SettingError("size", std::to_string(s.width) + "x" + std::to_string(s.height),
                           "each side must be between 1 and " + std::to_string(kMaxSide));
    // Every setting of the vocabulary within its range (SettingError names it).
    for (const SettingDef& def : settingsVocabulary()) checkSetting(def, def.get(s));
    if (!(s.terminationAlpha > 0.f && s.terminationAlpha <= 1.f))
        bad("early termination threshold must lie in (0, 1]");
    if (s.range && !(std::isfinite(s.range->first) && std::isfinite(s.range->second) &&
                     s.range->first <= s.range->second))
        throw SettingError("range", fmtValue(s.range->first) + "," + fmtValue(s.range->second),
                           "expected finite lo <= hi");
    if (s.tfTableSize < 2 || s.tfTableSize > (1 << 20))
        bad("transfer function table size out of range");
    if (s.tf.colors.empty() || s.tf.opacities.empty())
        bad("transfer function needs at least one colour and one opacity point");
    if (s.camera) validateCamera(*s.camera);
    if (s.tf.logScale && s.range && !(s.range->second > 0.f))  // the field's range: at setup
        refuseLogRange(true, s.range->first, s.range->second);
}

std::vector<PartitionShading> computePartitionShading(const KdPartitions& kd,
                                                      const std::vector<float>& gradientSpread,
                                                      const TfRangeView& range,
                                                      const StepRuleParams& rule) {
    const std::size_t n = kd.partitions.size();
    UVR_CHECK(gradientSpread.size() == n, "partition gradient spreads missing");
    std::vector<RangeStats> stats(n);
    float lo = INFINITY, hi = -INFINITY;
    for (std::size_t p = 0; p < n; ++p) {
        stats[p] = range.query(kd.partitions[p].valueMin, kd.partitions[p].valueMax);
        if (stats[p].maxOpacity > 0.f)
            lo = std::fmin(lo, stats[p].variance), hi = std::fmax(hi, stats[p].variance);
    }
    std::vector<PartitionShading> out(n);
    for (std::size_t p = 0; p < n; ++p)
        out[p] = shadePartition(stats[p], gradientSpread[p], lo, hi, rule);
    return out;
}

std::vector<PartitionShading> computeMacroShading(const MacroGrids& macro, const TfRangeView& range,
                                                  const StepRuleParams& rule) {
    const std::int64_t n = static_cast<std::int64_t>(macro.cells.size());
    std::vector<PartitionShading> out(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t c = 0; c < n; ++c) out[c] = shadeMacroCell(macro.cells[c], range, rule);
    return out;
}

bool usesMacroCells(const PreparedMesh& mesh, const StepRuleParams& rule) {
    return mesh.macro && rule.rule == StepRule::ErrorBound && rule.adaptive;
}

TfTableView FrameSetup::tfView() const {
    TfTableView t{tfTable.data(), static_cast<int>(tfTable.size()), rangeLo, rangeHi,
                  tfBreaks.data()};
    t.nan = tfNan;
    t.law = opacityLaw;
    return t;
}

SceneView FrameSetup::scene(const PreparedMesh& mesh) const {
    SceneView v;
    v.locator = mesh.locator();
    v.tf = tfView();
    v.bounds = mesh.tets.bounds;
    v.params = params;
    return v;
}

PartitionSceneView FrameSetup::partitionScene(const PreparedMesh& mesh, bool skip) const {
    UVR_CHECK(mesh.kd && shading.size() == mesh.kd->partitions.size(),
              "partition scene without partitions or shading");
    PartitionSceneView v;
    v.base = scene(mesh);
    v.kd = mesh.kd->view();
    v.cells = mesh.cellTree.view();
    if (mesh.seeds) v.seeds = mesh.seeds->view();
    v.shading = shading.data();
    v.skipTransparent = skip;
    if (!macroShading.empty()) {
        UVR_CHECK(mesh.macro && macroShading.size() == mesh.macro->cells.size(),
                  "macrocell shading without macrocells");
        v.macro = {mesh.macro->grids.data(), macroShading.data()};
    }
    return v;
}

namespace {

/// Most sample grid steps t / s1 from the camera to any point of the mesh: the integrators count
/// grid points in float, which counts exactly only up to 2^24.
constexpr double kMaxGridSteps = 16e6;

std::string fmtG(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

/// Refuses a frame whose estimated work (every ray across the bounds' diagonal) exceeds
/// kMaxSamplesPerRay or kMaxFrameSamples, naming the step that would be accepted.
void checkFrameWork(const PreparedMesh& mesh, const RenderSettings& settings, float step) {
    const Bounds3f& bounds = mesh.tets.bounds;
    const int raysPerPixel = settings.supersample * settings.supersample;
    const FrameWork w =
        estimateFrameWork(bounds, step, settings.width, settings.height, raysPerPixel);
    if (w.samplesPerRay <= kMaxSamplesPerRay && w.samples <= kMaxFrameSamples) return;
    const double pixels = double(settings.width) * settings.height * raysPerPixel;
    // Lengths shown in the file's units (the mesh renders scaled by frame.scale).
    const double unit = 1.0 / mesh.tets.frame.scale;
    const double diagonal = bounds.diagonal() * unit;
    // The smallest step within both caps, rounded up to two significant digits.
    const double least =
        std::max(diagonal / kMaxSamplesPerRay, diagonal * pixels / kMaxFrameSamples);
    const double scale = std::pow(10.0, std::floor(std::log10(least)) - 1.0);
    const double suggest = std::ceil(least / scale * 1.0001) * scale;
    const std::string what = settings.step > 0.f ? "`step` " + fmtG(step * unit)
                                                 : "the default step " + fmtG(step * unit) +
                                                       " (from the mean cell size)";
    throwError(ErrorKind::Argument, "",
               what + " would take up to " + fmtG(w.samples) + " samples (" +
                   std::to_string(settings.width) + "x" + std::to_string(settings.height) +
                   " pixels x " +
                   (raysPerPixel > 1 ? std::to_string(raysPerPixel) + " rays (`supersample` " +
                                           std::to_string(settings.supersample) + ") x "
                                     : std::string()) +
                   fmtG(w.samplesPerRay) + " per ray across the bounds' diagonal " +
                   fmtG(diagonal) + "), more than the " +
                   (w.samplesPerRay > kMaxSamplesPerRay ? "100,000 samples per ray"
                                                        : "10^12 samples per frame") +
                   " allowed: use `step` " + fmtG(suggest) + " or larger" +
                   (settings.step > 0.f
                        ? " (the default here is " + fmtG(defaultStep(mesh.tets) * unit) + ")"
                        : std::string()));
}

}  // namespace

FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu) {
    validateSettings(settings);
    FrameSetup f;
    f.method = resolveMethod(mesh, settings, gpu);
    const RenderMethod method = f.method.method;
    f.rangeLo = settings.range ? settings.range->first : mesh.tets.valueMin;
    f.rangeHi = settings.range ? settings.range->second : mesh.tets.valueMax;
    // The baked table: linear in the value over [rangeLo, rangeHi]; a log-scale function is
    // evaluated at each entry's log position, on a table fine enough where log changes fastest.
    int tableSize = settings.tfTableSize;
    if (settings.tf.logScale) {
        const std::string range = "[" + fmtValue(f.rangeLo) + ", " + fmtValue(f.rangeHi) + "]";
        const std::string which = settings.range ? "`range` " : "the field's range ";
        if (!(f.rangeHi > 0.f)) refuseLogRange(settings.range.has_value(), f.rangeLo, f.rangeHi);
        if (!(f.rangeLo > 0.f)) {
            f.rangeLo = std::fmin(f.rangeHi * 1e-4f, 1.f);  // ParaView's AdjustRangeForLog
            f.notes.push_back("`log`: " + which + range + " is not positive; mapping [" +
                              fmtValue(f.rangeLo) + ", " + fmtValue(f.rangeHi) +
                              "] as ParaView does (values below take the lowest colour; "
                              "set the range with `range` LO,HI)");
        }
        tableSize = logTableSize(settings.tfTableSize, f.rangeLo, f.rangeHi);
        // Below `resolved` one table step spans more than 1 / 255 of the log range: 8-bit
        // colour bands may show there (said when that is more than the range's lowest octave).
        const double resolved = logTableResolvedFrom(tableSize, 256, f.rangeLo, f.rangeHi);
        if (resolved > 2.0 * f.rangeLo)
            f.notes.push_back("`log` over " + fmtG(std::log10(double(f.rangeHi) / f.rangeLo)) +
                              " decades: the " + std::to_string(tableSize) +
                              "-entry table steps by more than 1/255 of the log range below "
                              "value " +
                              fmtValue(resolved) + " (narrow the range with `range` LO,HI)");
    }
    f.tfTable = settings.tf.bakeOverRange(tableSize, f.rangeLo, f.rangeHi);
    f.tfBreaks = tfTableBreaks(f.tfTable.data(), static_cast<int>(f.tfTable.size()));
    f.tfNan = Vec4f(settings.tf.nanColor.x, settings.tf.nanColor.y, settings.tf.nanColor.z,
                    settings.tf.nanOpacity);
    f.opacityLaw = settings.opacityLaw;
    const float aspect = float(settings.width) / float(settings.height);
    // Settings are in the file's units; the prepared mesh is in rendering units (mesh.tets.frame:
    // the identity unless the mesh is very large, very small or far from the origin).
    const MeshFrame& frame = mesh.tets.frame;
    f.frame = frame;
    const Bounds3f& bounds = mesh.tets.bounds;
    const bool empty = mesh.tets.cellCount() == 0;
    if (empty && !settings.camera)
        throwError(ErrorKind::Argument, "",
                   "the mesh has no cell of non-zero volume (every cell is flat or uses NaN/Inf "
                   "points): nothing to render");
    const auto toLocal = [&](float length, const char* setting) {
        const double v = double(length) * frame.scale;
        if (!frame.identity() && !(v >= double(FLT_MIN) && v <= double(FLT_MAX)))
            throw SettingError(setting, fmtG(length),
                               "out of float32 range against the mesh, which renders scaled by " +
                                   fmtG(frame.scale) + " (it is " +
                                   fmtG(bounds.diagonal() / frame.scale) + " across)");
        return static_cast<float>(v);
    };
    f.params.step = settings.step > 0.f ? toLocal(settings.step, "step") : defaultStep(mesh.tets);
    f.params.opacityUnit = settings.opacityUnit > 0.f
                               ? toLocal(settings.opacityUnit, "opacity_unit")
                               : defaultOpacityUnit(bounds, mesh.sourceCells);
    f.params.terminationAlpha = settings.terminationAlpha;
    f.params.preintegrated = settings.preintegrated;
    f.maxStep = settings.maxStep > 0.f ? toLocal(settings.maxStep, "max_step")
                                       : std::fmin(kDefaultMaxStepFactor * f.params.step, FLT_MAX);
    if (f.maxStep < f.params.step)
        throw SettingError(
            "max_step", fmtG(f.maxStep / frame.scale),
            "below `step` " + fmtG(f.params.step / frame.scale) + " (s2 must be >= s1)");
    // The camera in rendering units (the reset camera is in them already), in double until it
    // is known to fit float.
    const Camera given = settings.camera ? *settings.camera : resetCamera(bounds, aspect);
    const MeshFrame cameraFrame = settings.camera ? frame : MeshFrame{};
    double position[3], focal[3];
    cameraFrame.toLocal(given.position, position);
    cameraFrame.toLocal(given.focalPoint, focal);
    // Parallel projection: the rays start on the plane through the camera perpendicular to the
    // view direction (VTK's near clipping plane never lies behind the camera), moved forward to
    // the mesh's nearest corner when the mesh lies wholly in front of it: nothing between is
    // seen, and the sample grid then counts from the mesh, however far the camera is.
    const bool parallel = given.parallelProjection;
    double nearDistance = 0.0;
    // The integrators count sample grid points k = t / s1 from the ray origin in float: at 2^24
    // and beyond, k + 1 == k and a ray would never end. Refuse a camera that many steps from the
    // mesh's farthest corner (a camera far out with a narrow view angle, or a tiny --step).
    if (!empty) {
        // One pass over the bounds' corners: their depths along the view direction (parallel)
        // and their distances from the camera (perspective).
        double dir[3], len2 = 0.0;
        for (int a = 0; a < 3; ++a) dir[a] = focal[a] - position[a], len2 += dir[a] * dir[a];
        const double len = std::sqrt(len2);
        double nearest = INFINITY, farDepth = -INFINITY, farthestCorner = 0.0;
        for (int c = 0; c < 8; ++c) {
            const Vec3f corner((c & 1) ? bounds.hi.x : bounds.lo.x,
                               (c & 2) ? bounds.hi.y : bounds.lo.y,
                               (c & 4) ? bounds.hi.z : bounds.lo.z);
            double depth = 0.0, d2 = 0.0;
            for (int a = 0; a < 3; ++a) {
                const double d = corner[a] - position[a];
                depth += d * dir[a] / len;
                d2 += d * d;
            }
            nearest = std::min(nearest, depth);
            farDepth = std::max(farDepth, depth);
            farthestCorner = std::max(farthestCorner, std::sqrt(d2));
        }
        if (parallel && nearest > 0.0 && std::isfinite(nearest)) nearDistance = nearest;
        const double farthest = parallel ? std::max(0.0, farDepth - nearDistance) : farthestCorner;
        const double steps = farthest / f.params.step;
        if (!(steps <= kMaxGridSteps))
            throwError(ErrorKind::Argument, "",
                       parallel ? "the mesh is " + fmtG(steps) + " steps of " +
                                      fmtG(f.params.step / frame.scale) +
                                      " deep along the view direction (at most 16 million): use "
                                      "a larger `step`"
                                : "the camera is " + fmtG(steps) + " steps of " +
                                      fmtG(f.params.step / frame.scale) +
                                      " from the far side of the mesh (at most 16 million): move "
                                      "the camera closer (and widen `view_angle`) or use a "
                                      "larger `step`");
    }
    f.camera = given;
    f.camera.position = Vec3f(float(position[0]), float(position[1]), float(position[2]));
    f.camera.focalPoint = Vec3f(float(focal[0]), float(focal[1]), float(focal[2]));
    if (!isFinite(f.camera.position) || !isFinite(f.camera.focalPoint))
        throwError(ErrorKind::Argument, "",
                   "the camera lies beyond float32 range from the mesh, which renders scaled by " +
                       fmtG(frame.scale) + ": move the camera closer");
    if (parallel) {
        const double scale = double(given.parallelScale) * cameraFrame.scale;
        if (!(scale >= double(FLT_MIN) && scale <= double(FLT_MAX)))
            throwError(ErrorKind::Argument, "",
                       "parallel scale " + fmtG(given.parallelScale) +
                           ": out of float32 range against the mesh, which renders scaled by " +
                           fmtG(frame.scale));
        f.camera.parallelScale = static_cast<float>(scale);
    }
    validateCamera(f.camera);
    f.rays = makeCameraRays(f.camera, settings.width, settings.height, nearDistance);
    if (method == RenderMethod::Partitions && !mesh.kd)
        throwError(ErrorKind::Argument, "", "the partition method needs k-d partitions");
    if (method != RenderMethod::Partitions && mesh.bvh.nodes.empty() && mesh.tets.cellCount() != 0)
        throwError(ErrorKind::Argument, "",
                   std::string(method == RenderMethod::Exact ? "the exact" : "the reference") +
                       " method needs the mesh BVH");
    f.stepRule.rule = settings.stepRule;
    f.stepRule.adaptive = settings.adaptive;
    f.stepRule.s1 = f.params.step;
    f.stepRule.s2 = f.maxStep;
    f.stepRule.power = settings.power;
    f.stepRule.tolerance = toleranceForQuality(settings.quality);
    f.stepRule.valuePerEntry =
        static_cast<float>((double(f.rangeHi) - double(f.rangeLo)) / (f.tfTable.size() - 1));
    if (method == RenderMethod::Partitions && !gpu) {
        const auto start = std::chrono::steady_clock::now();
        const TfTableView table = f.tfView();
        const TfRangeTables ranges(table);
        f.shading =
            computePartitionShading(*mesh.kd, mesh.gradientSpread, ranges.view(table), f.stepRule);
        // Partitions and macrocells holding NaN values (their value ranges leave NaN out).
        for (std::size_t p = 0; p < mesh.partitionNan.size(); ++p)
            if (mesh.partitionNan[p]) shadeNan(f.shading[p], f.tfNan.w, f.stepRule.s1);
        if (usesMacroCells(mesh, f.stepRule)) {
            f.macroShading = computeMacroShading(*mesh.macro, ranges.view(table), f.stepRule);
            for (std::size_t c = 0; c < mesh.macro->nanCells.size(); ++c)
                if (mesh.macro->nanCells[c]) shadeNan(f.macroShading[c], f.tfNan.w, f.stepRule.s1);
            for (std::size_t p = 0; p < f.shading.size(); ++p)
                f.shading[p].byMacroCells =
                    macroCellsPay(mesh.macro->grids[p], f.macroShading.data(), f.shading[p]);
        }
        f.tfUpdateSeconds = secondsSince(start);
    }
    checkFrameWork(mesh, settings, f.params.step);
    return f;
}

FrameWork estimateFrameWork(const Bounds3f& bounds, float step, int width, int height,
                            int raysPerPixel) {
    FrameWork w;
    const double diagonal = bounds.empty() ? 0.0 : bounds.diagonal();
    if (!(diagonal > 0.0)) return w;
    w.samplesPerRay = step > 0.f ? diagonal / step : INFINITY;
    w.samples =
        w.samplesPerRay * std::max(width, 0) * std::max(height, 0) * std::max(raysPerPixel, 1);
    return w;
}

}  // namespace uvr

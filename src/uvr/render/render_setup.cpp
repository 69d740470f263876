// SPDX-License-Identifier: MIT
#include "uvr/render/render_setup.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"

namespace uvr {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

PreparedMesh prepareMesh(const Mesh& mesh, const ScalarField& field, const PrepareOptions& options,
                         const ProgressFn& progress) {
    PreparedMesh out;
    out.sourceCells = mesh.cellCount();
    auto start = std::chrono::steady_clock::now();
    if (progress)
        progress("splitting " + std::to_string(mesh.cellCount()) + " cells into tetrahedra");
    out.tets = tetrahedralize(mesh, field);
    out.splitSeconds = secondsSince(start);

    // The other builders (the GPU's) only where the mesh is large enough to pay.
    const bool elsewhere = out.tets.tets.size() >= options.builderMinTets;
    const LbvhBuilder lbvh = elsewhere ? options.lbvh : nullptr;
    const KdSplitter splitter = elsewhere ? options.kdSplitter : nullptr;
    out.builtElsewhere = elsewhere && (lbvh || splitter);
    if (options.meshBvh) {
        start = std::chrono::steady_clock::now();
        if (progress)
            progress("building the BVH over " + std::to_string(out.tets.tets.size()) +
                     " tetrahedra" + (lbvh ? " (LBVH on " + options.builderDevice + ")" : ""));
        if (lbvh) {
            out.bvh = buildMeshLbvh(out.tets, lbvh);
        } else {
            std::vector<Bounds3f> boxes;
            std::vector<Vec3f> centers;
            tetBoxesAndCenters(out.tets, boxes, centers);
            out.bvh = buildBvh(boxes, centers);
        }
        out.bvhSeconds = secondsSince(start);
    }

    start = std::chrono::steady_clock::now();
    if (progress) progress("finding face neighbours");
    out.neighbors = buildTetNeighbors(out.tets);
    out.adjacencySeconds = secondsSince(start);

    if (options.partitions) {
        if (progress)
            progress("building k-d partitions (up to " + std::to_string(options.kd.leafCells) +
                     " cells each" +
                     (out.builtElsewhere ? ", on " + options.builderDevice : std::string()) + ")");
        KdBuildOptions kd = options.kd;
        if (lbvh) kd.lbvh = lbvh;
        if (splitter) kd.splitter = splitter;
        out.kd = buildKdPartitions(out.tets, kd);
        if (options.seedGrids) {
            if (progress) progress("building seed grids");
            out.seeds = buildSeedGrids(out.tets, *out.kd);
        }
    }
    return out;
}

PreparedMesh prepareMesh(const Mesh& mesh, const ScalarField& field) {
    const PrepareOptions defaults;
    return prepareMesh(mesh, field, defaults);
}

float defaultStep(const TetMesh& mesh) {
    if (mesh.tets.empty() || !(mesh.totalVolume > 0.0))
        return 0.01f * std::fmax(mesh.bounds.diagonal(), 1e-30f);
    return static_cast<float>(0.5 * std::cbrt(mesh.totalVolume / double(mesh.tets.size())));
}

float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount) {
    const double d = bounds.diagonal();
    if (cellCount == 0 || !(d > 0.0)) return 1.f;
    return static_cast<float>(d / std::cbrt(double(cellCount)));
}

void validateSettings(const RenderSettings& s) {
    auto bad = [](const std::string& msg) { throwError(ErrorKind::Argument, "", msg); };
    constexpr int kMaxSide = 16384;
    if (s.width < 1 || s.height < 1 || s.width > kMaxSide || s.height > kMaxSide)
        bad("--size " + std::to_string(s.width) + "x" + std::to_string(s.height) +
            ": each side must be between 1 and " + std::to_string(kMaxSide));
    if (!std::isfinite(s.step) || s.step < 0.f)
        bad("--step " + std::to_string(s.step) + ": expected a positive finite distance");
    if (!std::isfinite(s.opacityUnit) || s.opacityUnit < 0.f)
        bad("--opacity-unit " + std::to_string(s.opacityUnit) +
            ": expected a positive finite distance");
    if (!(s.terminationAlpha > 0.f && s.terminationAlpha <= 1.f))
        bad("early termination threshold must lie in (0, 1]");
    if (s.range && !(std::isfinite(s.range->first) && std::isfinite(s.range->second) &&
                     s.range->first <= s.range->second))
        bad("--range " + std::to_string(s.range->first) + "," + std::to_string(s.range->second) +
            ": expected finite lo <= hi");
    if (!std::isfinite(s.maxStep) || s.maxStep < 0.f)
        bad("--max-step " + std::to_string(s.maxStep) + ": expected a positive finite distance");
    if (!(s.power >= 1.f && s.power <= 64.f))
        bad("--power " + std::to_string(s.power) + ": expected a number in [1, 64]");
    if (s.tfTableSize < 2 || s.tfTableSize > (1 << 20))
        bad("transfer function table size out of range");
    if (s.tf.colors.empty() || s.tf.opacities.empty())
        bad("transfer function needs at least one colour and one opacity point");
    if (s.camera) validateCamera(*s.camera);
}

std::vector<PartitionShading> computePartitionShading(const KdPartitions& kd,
                                                      const TfRangeView& range, float s1, float s2,
                                                      float power, bool adaptive) {
    const std::size_t n = kd.partitions.size();
    std::vector<RangeStats> stats(n);
    float lo = INFINITY, hi = -INFINITY;
    for (std::size_t p = 0; p < n; ++p) {
        stats[p] = range.query(kd.partitions[p].valueMin, kd.partitions[p].valueMax);
        if (stats[p].maxOpacity > 0.f)
            lo = std::fmin(lo, stats[p].variance), hi = std::fmax(hi, stats[p].variance);
    }
    std::vector<PartitionShading> out(n);
    for (std::size_t p = 0; p < n; ++p)
        out[p] = shadePartition(stats[p], lo, hi, s1, s2, power, adaptive);
    return out;
}

SceneView FrameSetup::scene(const PreparedMesh& mesh) const {
    SceneView v;
    v.locator = mesh.locator();
    v.tf = {tfTable.data(), static_cast<int>(tfTable.size()), rangeLo, rangeHi};
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
    if (mesh.seeds) v.seeds = mesh.seeds->view();
    v.shading = shading.data();
    v.skipTransparent = skip;
    return v;
}

namespace {

/// Most sample grid steps t / s1 from the camera to any point of the mesh: the integrators count
/// grid points in float, which counts exactly only up to 2^24.
constexpr double kMaxGridSteps = 16e6;

}  // namespace

FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings,
                          bool shadePartitions) {
    validateSettings(settings);
    FrameSetup f;
    f.tfTable = settings.tf.bake(settings.tfTableSize);
    f.rangeLo = settings.range ? settings.range->first : mesh.tets.valueMin;
    f.rangeHi = settings.range ? settings.range->second : mesh.tets.valueMax;
    const float aspect = float(settings.width) / float(settings.height);
    f.camera = settings.camera ? *settings.camera : resetCamera(mesh.tets.bounds, aspect);
    validateCamera(f.camera);
    f.rays = makeCameraRays(f.camera, settings.width, settings.height);
    f.params.step = settings.step > 0.f ? settings.step : defaultStep(mesh.tets);
    f.params.opacityUnit = settings.opacityUnit > 0.f
                               ? settings.opacityUnit
                               : defaultOpacityUnit(mesh.tets.bounds, mesh.sourceCells);
    f.params.terminationAlpha = settings.terminationAlpha;
    // A ray of the bounds' diagonal must not need more samples than a float counts exactly.
    f.maxStep = settings.maxStep > 0.f ? settings.maxStep : kDefaultMaxStepFactor * f.params.step;
    if (f.maxStep < f.params.step)
        throwError(ErrorKind::Argument, "",
                   "--max-step " + std::to_string(f.maxStep) + " is below --step " +
                       std::to_string(f.params.step) + " (s2 must be >= s1)");
    if (settings.method == RenderMethod::Partitions && !mesh.kd)
        throwError(ErrorKind::Argument, "", "the partition method needs k-d partitions");
    if (settings.method == RenderMethod::Reference && mesh.bvh.nodes.empty() &&
        !mesh.tets.tets.empty())
        throwError(ErrorKind::Argument, "", "the reference method needs the mesh BVH");
    if (settings.method == RenderMethod::Partitions && shadePartitions) {
        const auto start = std::chrono::steady_clock::now();
        const TfTableView table{f.tfTable.data(), static_cast<int>(f.tfTable.size()), f.rangeLo,
                                f.rangeHi};
        const TfRangeTables ranges(table);
        f.shading = computePartitionShading(*mesh.kd, ranges.view(table), f.params.step, f.maxStep,
                                            settings.power, settings.adaptive);
        f.tfUpdateSeconds = secondsSince(start);
    }
    // The integrators count sample grid points k = t / s1 from the camera in float: at 2^24 and
    // beyond, k + 1 == k and a ray would never end. Refuse a camera that many steps from the
    // mesh's farthest corner (a camera far out with a narrow view angle, or a tiny --step).
    double farthest = 0.0;
    for (int c = 0; c < 8; ++c) {
        const Bounds3f& b = mesh.tets.bounds;
        const Vec3f corner((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                           (c & 4) ? b.hi.z : b.lo.z);
        farthest = std::max(farthest, double(length(corner - f.camera.position)));
    }
    if (farthest / f.params.step > kMaxGridSteps)
        throwError(ErrorKind::Argument, "",
                   "the camera is " +
                       std::to_string(static_cast<long long>(farthest / f.params.step)) +
                       " steps of " + std::to_string(f.params.step) +
                       " from the far side of the mesh (at most 16 million): move the camera "
                       "closer (and widen --view-angle) or use a larger --step");
    const double samplesPerRay = mesh.tets.bounds.diagonal() / f.params.step;
    if (samplesPerRay > 1e7)
        throwError(ErrorKind::Argument, "",
                   "--step " + std::to_string(f.params.step) + " would take " +
                       std::to_string(static_cast<long long>(samplesPerRay)) +
                       " samples per ray (at most 10 million)");
    return f;
}

}  // namespace uvr

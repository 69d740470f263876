// SPDX-License-Identifier: MIT
#include "uvr/render/frame_setup.h"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <string>
#include <tuple>

#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/render/settings_vocabulary.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

ResolvedMethod resolveMethod(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu) {
    if (settings.method != RenderMethod::Auto) return {settings.method, ""};
    if (tunesAdaptive(settings))
        return {RenderMethod::Partitions, "auto: adaptive (the settings tune its sampling)"};
    const AutoMethodChoice choice = mesh.autoChoice && mesh.autoChoice->gpu == gpu
                                        ? *mesh.autoChoice
                                    : !mesh.piece ? autoMethod(mesh.tets, gpu)
                                    : gpu         ? mesh.piece->autoGpu
                                                  : mesh.piece->autoCpu;
    const bool bvh = !mesh.bvh.nodes.empty(), kd = mesh.kd.has_value();
    if (choice.method == RenderMethod::Exact && !bvh && kd)
        return {RenderMethod::Partitions,
                choice.reason() + "; adaptive: the mesh BVH exact needs was not prepared"};
    if (choice.method == RenderMethod::Partitions && !kd && bvh)
        return {RenderMethod::Exact,
                choice.reason() + "; exact: the partitions adaptive needs were not prepared"};
    const bool weighs = choice.method == RenderMethod::Partitions && bvh && kd && !mesh.piece;
    return {choice.method, choice.reason(), weighs ? choice.adaptiveSampleCost : 0.0};
}

SampleEstimate estimateSamples(const KdPartitions& kd, const std::vector<PartitionShading>& shading,
                               const std::vector<float>& macroDensity, float s1) {
    UVR_CHECK(shading.size() == kd.partitions.size(), "partition shading missing");
    SampleEstimate e;
    for (std::size_t p = 0; p < shading.size(); ++p) {
        const double volume = kd.partitions[p].box.volume();
        if (!(volume > 0.0)) continue;
        const PartitionShading& s = shading[p];
        double density = 0.0;
        if (s.byMacroCells && p < macroDensity.size())
            density = macroDensity[p];
        else if (s.maxOpacity > 0.f && s.step > 0.f)
            density = 1.0 / s.step;
        e.adaptive += volume * density;
        e.reference += volume / s1;
        if (s.maxOpacity > 0.f && s.step < s1) e.finer += volume;
    }
    return e;
}

void weighReference(FrameSetup& f, const PreparedMesh& mesh, const std::vector<float>& macroDensity,
                    bool gpu) {
    const double cost = f.method.weighReference;
    f.method.weighReference = 0.0;
    if (!(cost > 0.0) || !mesh.kd) return;
    const SampleEstimate e = estimateSamples(*mesh.kd, f.shading, macroDensity, f.stepRule.s1);
    if (e.finer > 0.0) {
        f.method.reason +=
            "; adaptive: under this transfer function its error bound asks for "
            "steps below s1 in " +
            formatG(100.0 * e.finer / e.reference / f.stepRule.s1, 2) +
            "% of the partitions' volume, which the reference's s1 would miss";
        return;
    }
    const double saving = e.adaptive > 0.0 ? e.reference / e.adaptive : INFINITY;
    const bool reference = saving < cost;
    f.method.reason += std::string("; ") + (reference ? "reference" : "adaptive") +
                       ": under this transfer function adaptive would take " +
                       (std::isfinite(saving) ? formatG(saving, 3) + "x fewer" : "no") +
                       " samples than the reference, " + (reference ? "under" : "at least") +
                       " the " + formatG(cost, 3) + "x its sample costs on the " +
                       (gpu ? "GPU" : "CPU");
    if (reference) f.method.method = RenderMethod::Reference;
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
    v.bounds =
        mesh.wholeBounds();  // a data-parallel piece: the whole mesh's, as one process cuts rays
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

/// Refuses a frame whose estimated work (every ray across the bounds' diagonal) exceeds
/// kMaxSamplesPerRay or kMaxFrameSamples, naming the step that would be accepted.
void checkFrameWork(const PreparedMesh& mesh, const RenderSettings& settings, float step) {
    const Bounds3f& bounds = mesh.wholeBounds();
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
    const std::string what = settings.step > 0.f ? "`sample_distance` " + formatG(step * unit, 3)
                                                 : "the default step " + formatG(step * unit, 3) +
                                                       " (from the mean cell size)";
    throwError(
        ErrorKind::Argument, "",
        what + " would take up to " + formatG(w.samples, 3) + " samples (" +
            std::to_string(settings.width) + "x" + std::to_string(settings.height) + " pixels x " +
            (raysPerPixel > 1 ? std::to_string(raysPerPixel) + " rays (`supersample` " +
                                    std::to_string(settings.supersample) + ") x "
                              : std::string()) +
            formatG(w.samplesPerRay, 3) + " per ray across the bounds' diagonal " +
            formatG(diagonal, 3) + "), more than the " +
            (w.samplesPerRay > kMaxSamplesPerRay ? "100,000 samples per ray"
                                                 : "10^12 samples per frame") +
            " allowed: use `sample_distance` " + formatG(suggest, 3) + " or larger" +
            (settings.step > 0.f
                 ? " (the default here is " + formatG(mesh.wholeDefaultStep() * unit, 3) + ")"
                 : std::string()));
}

}  // namespace

std::pair<float, float> frameValueRange(const PreparedMesh& mesh, const RenderSettings& settings) {
    float lo = settings.range ? settings.range->first : mesh.wholeValueMin();
    const float hi = settings.range ? settings.range->second : mesh.wholeValueMax();
    if (settings.tf.logScale && hi > 0.f && !(lo > 0.f))
        lo = std::fmin(hi * 1e-4f, 1.f);  // ParaView's AdjustRangeForLog
    return {lo, hi};
}

FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu) {
    validateSettings(settings);
    FrameSetup f;
    f.method = resolveMethod(mesh, settings, gpu);
    const RenderMethod method = f.method.method;
    std::tie(f.rangeLo, f.rangeHi) = frameValueRange(mesh, settings);
    // The baked table: linear in the value over [rangeLo, rangeHi]; a log-scale function is
    // evaluated at each entry's log position, on a table fine enough where log changes fastest.
    int tableSize = settings.tfTableSize;
    if (settings.tf.logScale) {
        const float given = settings.range ? settings.range->first : mesh.wholeValueMin();
        const std::string range = "[" + formatG(given, 6) + ", " + formatG(f.rangeHi, 6) + "]";
        const std::string which = settings.range ? "`range` " : "the field's range ";
        if (!(f.rangeHi > 0.f)) refuseLogRange(settings.range.has_value(), f.rangeLo, f.rangeHi);
        if (!(given > 0.f)) {  // frameValueRange moved it
            f.notes.push_back("`log`: " + which + range + " is not positive; mapping [" +
                              formatG(f.rangeLo, 6) + ", " + formatG(f.rangeHi, 6) +
                              "] as ParaView does (values below take the lowest colour; "
                              "set the range with `range` LO,HI)");
        }
        tableSize = logTableSize(settings.tfTableSize, f.rangeLo, f.rangeHi);
        // Below `resolved` one table step spans more than 1 / 255 of the log range: 8-bit
        // colour bands may show there (said when that is more than the range's lowest octave).
        const double resolved = logTableResolvedFrom(tableSize, 256, f.rangeLo, f.rangeHi);
        if (resolved > 2.0 * f.rangeLo)
            f.notes.push_back("`log` over " +
                              formatG(std::log10(double(f.rangeHi) / f.rangeLo), 3) +
                              " decades: the " + std::to_string(tableSize) +
                              "-entry table steps by more than 1/255 of the log range below "
                              "value " +
                              formatG(resolved, 6) + " (narrow the range with `range` LO,HI)");
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
    const Bounds3f& bounds = mesh.wholeBounds();
    const bool empty = mesh.tets.cellCount() == 0 && !mesh.piece;
    if (empty && !settings.camera)
        throwError(ErrorKind::Argument, "",
                   "the mesh has no cell of non-zero volume (every cell is flat or uses NaN/Inf "
                   "points): nothing to render");
    const auto toLocal = [&](float length, const char* setting) {
        const double v = double(length) * frame.scale;
        if (!frame.identity() && !(v >= double(FLT_MIN) && v <= double(FLT_MAX)))
            throw SettingError(setting, formatG(length, 3),
                               "out of float32 range against the mesh, which renders scaled by " +
                                   formatG(frame.scale, 3) + " (it is " +
                                   formatG(bounds.diagonal() / frame.scale, 3) + " across)");
        return static_cast<float>(v);
    };
    f.params.step =
        settings.step > 0.f ? toLocal(settings.step, "sample_distance") : mesh.wholeDefaultStep();
    // A data-parallel piece: the sample ending its last segment lies one sample distance past
    // its box, which its ghost cells must reach (exact cuts the cells at the box instead).
    if (mesh.piece && f.method.method != RenderMethod::Exact &&
        f.params.step > mesh.piece->ghost * 1.0001f)
        throw SettingError("sample_distance", formatG(settings.step, 4),
                           "expected at most " + formatG(mesh.piece->ghost / frame.scale, 4) +
                               " for these data-parallel pieces: their ghost cells reach that "
                               "far past each rank's box (give the largest sample distance "
                               "when preparing: `--sample-distance` on the command line)");
    if (settings.step > 0.f && !empty) {
        const double across = bounds.diagonal() / f.params.step;
        if (across < kFewSamplesAcross)
            f.notes.push_back("`sample_distance` " + formatG(settings.step, 3) + " takes " +
                              formatG(across, 2) + " samples across the mesh (its diagonal is " +
                              formatG(bounds.diagonal() / frame.scale, 3) +
                              "): the image is coarse; the default here is " +
                              formatG(mesh.wholeDefaultStep() / frame.scale, 3));
    }
    f.params.opacityUnit = settings.opacityUnit > 0.f
                               ? toLocal(settings.opacityUnit, "opacity_unit")
                               : defaultOpacityUnit(bounds, mesh.wholeSourceCells());
    f.params.terminationAlpha = settings.terminationAlpha;
    f.params.preintegrated = settings.preintegrated;
    f.params.clip = clipView(settings, frame);
    if (mesh.piece) f.params.piece = {true, mesh.piece->region};
    f.params.light = settings.lighting;  // directions only: the frame's scaling keeps them
    // A gradient's magnitude per rendering unit is the file's over the frame's scale.
    f.params.gradientOpacity = settings.gradientOpacity;
    GradientOpacity& gop = f.params.gradientOpacity;
    for (int i = 0; i < gop.count; ++i)
        gop.magnitude[i] = static_cast<float>(std::fmin(gop.magnitude[i] / frame.scale, FLT_MAX));
    f.params.iso = isoView(settings);
    f.params.depthAlpha = settings.depthAlpha;
    if (gop.active() && mesh.tets.association == Association::Cell)
        throw SettingError("gradient_opacity", gradientOpacityText(settings.gradientOpacity),
                           "a gradient opacity needs a point field, and '" + mesh.tets.fieldName +
                               "' is cell data (constant in each cell: its gradient is 0)");
    if (f.params.iso.active() && mesh.tets.association == Association::Cell)
        throw SettingError("iso", isoText(f.params.iso.surfaces[0]),
                           "isosurfaces need a point field, and '" + mesh.tets.fieldName +
                               "' is cell data (constant in each cell: it has no surfaces "
                               "inside a cell)");
    // (Frames that read the gradient limit their visible regions' steps by their opacity:
    // shadeLit, below.)
    f.maxStep = settings.maxStep > 0.f ? toLocal(settings.maxStep, "max_sample_distance")
                                       : std::fmin(kDefaultMaxStepFactor * f.params.step, FLT_MAX);
    if (f.maxStep < f.params.step)
        throw SettingError("max_sample_distance", formatG(f.maxStep / frame.scale, 3),
                           "below `sample_distance` " + formatG(f.params.step / frame.scale, 3) +
                               " (s2 must be >= s1)");
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
    // mesh's farthest corner (a camera far out with a narrow view angle, or a tiny sample
    // distance).
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
                       parallel ? "the mesh is " + formatG(steps, 3) + " steps of " +
                                      formatG(f.params.step / frame.scale, 3) +
                                      " deep along the view direction (at most 16 million): use "
                                      "a larger `sample_distance`"
                                : "the camera is " + formatG(steps, 3) + " steps of " +
                                      formatG(f.params.step / frame.scale, 3) +
                                      " from the far side of the mesh (at most 16 million): move "
                                      "the camera closer (and widen `view_angle`) or use a "
                                      "larger `sample_distance`");
    }
    f.camera = given;
    f.camera.position = Vec3f(float(position[0]), float(position[1]), float(position[2]));
    f.camera.focalPoint = Vec3f(float(focal[0]), float(focal[1]), float(focal[2]));
    if (!isFinite(f.camera.position) || !isFinite(f.camera.focalPoint))
        throwError(ErrorKind::Argument, "",
                   "the camera lies beyond float32 range from the mesh, which renders scaled by " +
                       formatG(frame.scale, 3) + ": move the camera closer");
    if (parallel) {
        const double scale = double(given.parallelScale) * cameraFrame.scale;
        if (!(scale >= double(FLT_MIN) && scale <= double(FLT_MAX)))
            throwError(ErrorKind::Argument, "",
                       "parallel scale " + formatG(given.parallelScale, 3) +
                           ": out of float32 range against the mesh, which renders scaled by " +
                           formatG(frame.scale, 3));
        f.camera.parallelScale = static_cast<float>(scale);
    }
    validateCamera(f.camera);
    f.rays = makeCameraRays(f.camera, settings.width, settings.height, nearDistance);
    f.viewDirection = normalize(f.camera.focalPoint - f.camera.position);
    f.rayStartDepth = parallel ? static_cast<float>(nearDistance) : 0.f;
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
    // Shaded with a light that depends on the normal, or with a gradient opacity, s2 left to
    // the default: shadeLit's limit. Where the gradient is noise a sample's light may be
    // anywhere within the light's rate, and its gradient opacity's scale anywhere between 0 and
    // the function's largest: their sum bounds how far what a step adds can be off, per unit
    // of its optical depth.
    const Lighting& light = settings.lighting;
    const float lightRate = light.on
                                ? std::fmax(light.diffuse, 0.f) + std::fmax(light.specular, 0.f) *
                                                                      std::sqrt(light.specularPower)
                                : 0.f;
    float scaleRate = 0.f;
    for (int i = 0; i < gop.count; ++i) scaleRate = std::fmax(scaleRate, gop.scale[i]);
    const float rate = lightRate + scaleRate;
    if (rate > 0.f && !(settings.maxStep > 0.f)) {
        f.stepRule.litStepScale = std::fmin(kLitError * f.params.opacityUnit / rate, FLT_MAX);
        f.stepRule.litMinStep = std::fmin(kShadedMaxStepFactor * f.params.step, f.maxStep);
    }
    if (method == RenderMethod::Partitions && !gpu) {
        const auto start = std::chrono::steady_clock::now();
        const TfTableView table = f.tfView();
        const TfRangeTables ranges(table);
        f.shading =
            computePartitionShading(*mesh.kd, mesh.gradientSpread, ranges.view(table), f.stepRule);
        // Partitions and macrocells holding NaN values (their value ranges leave NaN out).
        for (std::size_t p = 0; p < mesh.partitionNan.size(); ++p)
            if (mesh.partitionNan[p]) shadeNan(f.shading[p], f.tfNan.w, f.stepRule.s1);
        // Partitions and macrocells an isosurface crosses: visible, at s1.
        const IsoView& iso = f.params.iso;
        if (iso.active())
            for (std::size_t p = 0; p < f.shading.size(); ++p)
                shadeIso(f.shading[p], mesh.kd->partitions[p].valueMin,
                         mesh.kd->partitions[p].valueMax, iso, f.stepRule.s1);
        std::vector<float> macroDensity;  // per partition, with macrocells (weighReference's too)
        if (usesMacroCells(mesh, f.stepRule)) {
            f.macroShading = computeMacroShading(*mesh.macro, ranges.view(table), f.stepRule);
            for (std::size_t c = 0; c < mesh.macro->nanCells.size(); ++c)
                if (mesh.macro->nanCells[c]) shadeNan(f.macroShading[c], f.tfNan.w, f.stepRule.s1);
            if (iso.active())
                for (std::size_t c = 0; c < f.macroShading.size(); ++c)
                    shadeIso(f.macroShading[c], mesh.macro->cells[c].valueMin,
                             mesh.macro->cells[c].valueMax, iso, f.stepRule.s1);
            macroDensity.resize(f.shading.size());
            for (std::size_t p = 0; p < f.shading.size(); ++p) {
                macroDensity[p] = macroSampleDensity(mesh.macro->grids[p], f.macroShading.data());
                f.shading[p].byMacroCells = macroCellsPay(macroDensity[p], f.shading[p]);
            }
        }
        if (f.method.weighReference > 0.0) weighReference(f, mesh, macroDensity, /*gpu=*/false);
        f.tfUpdateSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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

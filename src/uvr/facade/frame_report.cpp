// SPDX-License-Identifier: MIT
#include "uvr/facade/frame_report.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <vector>

#include "uvr/cpu/threads.h"
#include "uvr/cuda/cuda_device.h"
#include "uvr/render/empty_frame.h"

namespace uvr {

nlohmann::json reportNumber(double v) {
    return std::fabs(v) <= FLT_MAX ? nlohmann::json(static_cast<float>(v)) : nlohmann::json(v);
}

namespace {

/// The k-d partitions' sizes and build (min, median and max cells: nth_element, no sort).
nlohmann::json partitionsReport(const PreparedMesh& prepared) {
    const KdPartitions& kd = *prepared.kd;
    std::vector<std::uint32_t> sizes;
    sizes.reserve(kd.partitions.size());
    for (const KdPartition& p : kd.partitions) sizes.push_back(p.cellCount);
    std::uint32_t lo = 0, median = 0, hi = 0;
    if (!sizes.empty()) {
        const auto [mn, mx] = std::minmax_element(sizes.begin(), sizes.end());
        lo = *mn, hi = *mx;
        std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
        median = sizes[sizes.size() / 2];
    }
    return {{"count", kd.partitions.size()},
            {"build_seconds", kd.buildSeconds},
            {"cells_min", lo},
            {"cells_median", median},
            {"cells_max", hi},
            {"duplication_factor", kd.duplicationFactor(prepared.tets.cellCount())},
            {"leaf_cells", kd.leafCells}};
}

}  // namespace

nlohmann::json frameReport(const Renderer& renderer, const RenderSettings& settings,
                           const RenderResult& result) {
    const PreparedMesh& prepared = renderer.prepared();
    const FrameSetup& setup = result.setup;
    const MeshFrame& frame = setup.frame;
    nlohmann::json j;
    j["field"] = prepared.tets.fieldName;
    j["field_association"] = associationName(prepared.tets.association);
    j["device"] = renderer.deviceName();
    if (!renderer.deviceFallback().empty()) j["device_fallback"] = renderer.deviceFallback();
    if (const std::optional<GpuResidency> gpu = renderer.gpuResidency()) {
        const double bytes = double(gpu->geometryBytes);
        j["gpu"] = {{"description", cudaDeviceDescription()},
                    {"geometry_bytes", gpu->geometryBytes},
                    {"bytes_per_cell",
                     bytes / double(std::max<std::uint64_t>(1, prepared.tets.cellCount()))},
                    // Per tetrahedron of the split (the cells' tetrahedra when split): comparable
                    // between native and split cells.
                    {"bytes_per_tetrahedron",
                     bytes / double(std::max<std::uint64_t>(1, prepared.tets.splitTetCount()))},
                    {"upload_seconds", gpu->uploadSeconds},
                    {"build_peak_bytes", gpu->buildPeakBytes}};
    }
    j["threads"] = cpu::threadCount();
    // The method that rendered; with auto, also what was asked and why.
    j["method"] = methodName(setup.method.method);
    if (!setup.method.reason.empty()) {
        j["method_asked"] = methodName(settings.method);
        j["method_reason"] = setup.method.reason;
    }
    if (setup.method.method != RenderMethod::Exact)
        j["sampling"] = samplingName(settings.preintegrated);
    if (prepared.kd) {
        j["partitions"] = partitionsReport(prepared);
        if (prepared.seeds)
            j["seed_grids"] = {{"cells", prepared.seeds->seeds.size()},
                               {"bytes", prepared.seeds->bytes()},
                               {"build_seconds", prepared.seeds->buildSeconds}};
        j["tf_update_seconds"] = setup.tfUpdateSeconds;
        j["max_sample_distance"] = reportNumber(setup.maxStep / frame.scale);
        j["step_rule"] = stepRuleName(settings.stepRule);
        if (settings.stepRule == StepRule::ErrorBound) {
            j["quality"] = settings.quality;
            j["tolerance"] = setup.stepRule.tolerance;
        } else {
            j["power"] = settings.power;
        }
        j["skip"] = settings.skip;
        j["adaptive"] = settings.adaptive;
        j["partitions_visited"] = result.stats.partitionsVisited;
        j["partitions_skipped"] = result.stats.partitionsSkipped;
    }
    j["image"] = {{"width", settings.width}, {"height", settings.height}};
    // Anti-aliasing: a pixel's samples are summed over its supersample^2 rays.
    j["supersample"] = settings.supersample;
    if (settings.supersample > 1) j["jitter"] = settings.jitter;
    // Clipping, in the file's coordinates as given.
    if (!settings.clipPlanes.empty()) {
        nlohmann::json planes = nlohmann::json::array();
        for (const ClipPlane& p : settings.clipPlanes)
            planes.push_back(
                {p.origin.x, p.origin.y, p.origin.z, p.normal.x, p.normal.y, p.normal.z});
        j["clip_planes"] = std::move(planes);
    }
    if (settings.clipBox)
        j["clip_box"] = {settings.clipBox->lo.x, settings.clipBox->lo.y, settings.clipBox->lo.z,
                         settings.clipBox->hi.x, settings.clipBox->hi.y, settings.clipBox->hi.z};
    if (settings.clipSurface && (!settings.clipPlanes.empty() || settings.clipBox))
        j["clip_surface"] = true;
    // Depth out and in.
    if (settings.depthAlpha > 0.f) j["depth_alpha"] = settings.depthAlpha;
    if (!settings.depthIn.empty()) j["depth_in"] = true;
    // Isosurfaces, as the CLI's --iso writes them.
    if (!settings.isoSurfaces.empty()) {
        nlohmann::json iso = nlohmann::json::array();
        for (const IsoSurface& s : settings.isoSurfaces) iso.push_back(isoText(s));
        j["iso"] = std::move(iso);
    }
    // Gradient shading, with its coefficients when on (they light isosurfaces and the cut face
    // too); the gradient opacity, as the CLI's --gradient-opacity writes it.
    j["shade"] = settings.lighting.on;
    if (settings.gradientOpacity.active())
        j["gradient_opacity"] = gradientOpacityText(settings.gradientOpacity);
    if (readsGradient(settings.lighting, settings.gradientOpacity))
        j["normals"] = settings.lighting.smooth ? "smooth" : "cell";
    if (settings.lighting.on || !settings.isoSurfaces.empty() || j.contains("clip_surface")) {
        j["normals"] = settings.lighting.smooth ? "smooth" : "cell";
        j["ambient"] = settings.lighting.ambient;
        j["diffuse"] = settings.lighting.diffuse;
        j["specular"] = settings.lighting.specular;
        j["specular_power"] = settings.lighting.specularPower;
    }
    j["rays"] = result.stats.rays();
    j["mesh"] = {{"tetrahedra", prepared.tets.tetCount()},
                 {"pyramids", prepared.tets.pyramidCount},
                 {"wedges", prepared.tets.wedgeCount},
                 {"hexahedra", prepared.tets.hexCount}};
    // Every phase of the preparation ("adjacency" is the neighbours' old name).
    j["prepare_seconds"] = {{"bvh", prepared.bvhSeconds}, {"adjacency", prepared.adjacencySeconds}};
    for (const auto& [phase, seconds] : prepared.phaseSeconds)
        j["prepare_seconds"][phase] = seconds;
    if (!prepared.builtOnCpuInstead.empty())
        j["prepare_on_cpu_instead"] = prepared.builtOnCpuInstead;
    j["render_seconds"] = result.stats.seconds;
    j["samples"] = result.stats.samples;
    j["mean_samples_per_pixel"] = result.stats.meanSamplesPerPixel();
    j["mean_samples_per_ray"] = result.stats.meanSamplesPerRay();
    j["max_samples_per_pixel"] =
        result.sampleCounts.empty()
            ? 0u
            : *std::max_element(result.sampleCounts.begin(), result.sampleCounts.end());
    j["samples_per_second"] =
        result.stats.seconds > 0 ? double(result.stats.samples) / result.stats.seconds : 0.0;
    j["walk_steps"] = result.stats.walkSteps;
    j["bvh_queries"] = result.stats.bvhQueries;
    if (!result.ranks.empty()) {
        // A data-parallel frame: each rank's share and how even they were.
        nlohmann::json ranks = nlohmann::json::array();
        double slowest = 0.0, total = 0.0;
        const std::vector<double>& prepare = renderer.rankPrepareSeconds();
        for (std::size_t i = 0; i < result.ranks.size(); ++i) {
            const RankFrameStats& r = result.ranks[i];
            ranks.push_back({{"frame_seconds", r.frameSeconds},
                             {"composite_seconds", r.compositeSeconds},
                             {"composite_bytes_sent", r.bytesSent},
                             {"samples", r.samples},
                             {"cells", r.cells},
                             {"rerendered_pixels", r.rerenderedPixels},
                             {"peak_host_bytes", r.peakHostBytes}});
            if (i < prepare.size()) ranks.back()["prepare_seconds"] = prepare[i];
            slowest = std::max(slowest, r.frameSeconds);
            total += r.frameSeconds;
        }
        j["ranks"] = std::move(ranks);
        j["imbalance"] = total > 0.0 ? slowest * double(result.ranks.size()) / total : 1.0;
    }
    // Lengths and positions in the file's units (the mesh may render scaled and moved).
    j["sample_distance"] = reportNumber(setup.params.step / frame.scale);
    j["opacity_unit"] = reportNumber(setup.params.opacityUnit / frame.scale);
    j["opacity_law"] = opacityLawName(settings.opacityLaw);
    j["range"] = {setup.rangeLo, setup.rangeHi};
    j["log_scale"] = settings.tf.logScale;
    j["tf_table_entries"] = setup.tfTable.size();
    const Camera& c = setup.camera;
    double position[3], focal[3];
    frame.toFile(c.position, position);
    frame.toFile(c.focalPoint, focal);
    j["camera"] = {
        {"position",
         {reportNumber(position[0]), reportNumber(position[1]), reportNumber(position[2])}},
        {"focal_point", {reportNumber(focal[0]), reportNumber(focal[1]), reportNumber(focal[2])}},
        {"view_up", {c.viewUp.x, c.viewUp.y, c.viewUp.z}},
        {"view_angle", c.viewAngle},
        {"parallel_projection", c.parallelProjection}};
    if (c.parallelProjection)
        j["camera"]["parallel_scale"] = reportNumber(c.parallelScale / frame.scale);
    j["notes"] = setup.notes;
    j["empty_frame"] = explainEmptyFrame(prepared, settings, result);
    return j;
}

}  // namespace uvr

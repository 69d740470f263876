// SPDX-License-Identifier: MIT
// `uvr bench`: the paper's evaluation (Morrical et al. 2019, Figs. 4-6) for one mesh, camera and
// transfer function: reference, skipping only, adaptive only, both, and a sweep over s2, each
// image compared with the exact integrator's (the yardstick, issue 11).

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "cli_common.h"
#include "progress.h"
#include "render_pipeline.h"
#include "uvr/core/text.h"
#include "uvr/cpu/threads.h"

namespace uvr::cli {

namespace {

/// One benchmarked configuration.
struct Variant {
    std::string name;
    std::string file;  ///< stem of its images under --images (fileName(name) unless set)
    RenderSettings settings;
    double s2Factor = 0.0;  ///< s2 / s1 (0 when not adaptive)
    // Results.
    double medianSeconds = 0.0;
    std::uint64_t samples = 0;
    ImageComparison cmp;  ///< against the exact image (exact's own: identical)
    RenderResult last;
};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// A readable file stem for a configuration name: lower-case letters, digits and dots, other
/// runs of characters as one '-' ("skipping + adaptive" -> "skipping-adaptive").
std::string fileName(const std::string& name) {
    std::string s;
    for (char c : name) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (std::isalnum(u) || c == '.')
            s += static_cast<char>(std::tolower(u));
        else if (!s.empty() && s.back() != '-')
            s += '-';
    }
    while (!s.empty() && s.back() == '-') s.pop_back();
    return s;
}

}  // namespace

void addBenchCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "bench",
        "Time reference, skipping only, adaptive only, both, and an s2 sweep on one mesh; "
        "print time per frame, samples, speed-up over the reference, and SSIM, the 99.9th "
        "percentile and maximum of the per-pixel difference and the seams against the exact "
        "integrator's image (the CSV and JSON add the pixels off and speckle)");
    auto file = std::make_shared<std::string>();
    auto flags = std::make_shared<RenderFlags>();
    auto repeat = std::make_shared<int>(5);
    auto sweep = std::make_shared<std::vector<double>>(std::vector<double>{2, 4, 8, 16, 32});
    auto csv = std::make_shared<std::string>();
    auto json = std::make_shared<std::string>();
    auto images = std::make_shared<std::string>();
    cmd->add_option("FILE", *file, kMeshFileHelp)->required();
    flags->registerOn(*cmd, /*oneFrame=*/false, /*withMethod=*/false);
    cmd->add_option("--repeat", *repeat, "Timed frames per configuration (median reported)")
        ->capture_default_str()
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--sweep", *sweep, "s2 / s1 factors of the sweep")
        ->delimiter(',')
        ->capture_default_str()
        ->check(CLI::Range(1.0, 1e4));
    cmd->add_option("--csv", *csv, "Write the table as CSV");
    cmd->add_option("--json", *json, "Write the table and settings as JSON");
    cmd->add_option("--images", *images,
                    "Write each configuration's image and sample heat map (all on the reference's "
                    "scale) into this folder");
    cmd->callback([=, &ctx] {
        applyThreads(flags->threads);
        std::vector<NamedFile> outputs;
        for (auto [flag, out] : {std::pair{"--csv", csv.get()}, std::pair{"--json", json.get()}}) {
            if (out->empty()) continue;
            if (*out == "-")
                throwError(ErrorKind::Argument, "-",
                           std::string(flag) +
                               ": bench prints its table on standard output; "
                               "name a file");
            outputs.push_back({flag, *out});
        }
        std::vector<NamedFile> inputs = flags->inputs();
        inputs.push_back({"the input mesh", *file});
        checkOutputsDistinct(inputs, outputs);
        for (const NamedFile& out : outputs) resolveOutput(out.path);
        // Every variant's last frame is kept until the table is printed.
        checkFrameEstimate(ctx,
                           "--size " + flags->size + ": the frames of " +
                               std::to_string(6 + sweep->size()) + " variants",
                           frameMemoryBytes(*flags, 6 + sweep->size()));
        if (!images->empty()) {  // made when missing, before any heavy work
            std::error_code ec;
            std::filesystem::create_directories(*images, ec);
            if (!std::filesystem::is_directory(*images))
                throwError(ErrorKind::Io, *images,
                           "--images: cannot make this folder" +
                               (ec ? ": " + ec.message() : std::string(" (a file has its name)")));
        }
        // Partitions are needed; the variants pick their integrators.
        flags->vocabulary.set("method", methodName(RenderMethod::Partitions));
        flags->checkBeforeLoading(*file);
        // One process reads the mesh; data-parallel ranks read their shares (readDistributed)
        // and time the composited frames, and rank 0 prints and writes.
        const bool root = ctx.root();
        std::optional<Mesh> mesh;
        std::optional<DistributedSource> share;
        if (ctx.dataParallel())
            share = readDistributed(*file, flags->field, StepFlags{}, ctx);
        else
            mesh = loadMesh(*file, ctx);
        const ScalarField field = share ? ScalarField{share->share.field.name,
                                                      share->share.field.association,
                                                      {},
                                                      share->share.field.choice}
                                        : selectScalarField(*mesh, parseFieldSpec(flags->field));
        ctx.step("field " + field.describe() + (field.choice.empty() ? "" : ", " + field.choice));
        std::vector<std::string> notes;
        const RenderSettings base =
            flags->settings(share ? share->source.summary.bounds : mesh->bounds(), *file, &notes);
        for (const std::string& note : notes) ctx.step("note: " + note);
        ctx.setActivity(*file, "preparing the mesh and rendering it");
        const std::optional<Vec3f> background = flags->backgroundColor();
        const Vec3f bg = background ? *background : Vec3f(0.f, 0.f, 0.f);
        RendererOptions options = flags->rendererOptions(/*withReference=*/true);
        std::unique_ptr<Renderer> rendererOwner;
        if (share) {
            options.communicator = ctx.comm;
            PhaseProgress phases(ctx);
            rendererOwner =
                std::make_unique<Renderer>(std::move(share->share), options, phases.callbacks());
        } else {
            rendererOwner = makeRenderer(*mesh, field, options, ctx);
        }
        Renderer& renderer = *rendererOwner;
        const PreparedMesh& prepared = renderer.prepared();
        const FrameSetup setup = makeFrameSetup(prepared, base);
        const float s1 = static_cast<float>(setup.params.step / setup.frame.scale);  // file units
        const float defaultS2 = base.maxStep > 0.f ? base.maxStep : kDefaultMaxStepFactor * s1;

        std::vector<Variant> variants;
        auto add = [&](const std::string& name, RenderMethod method, bool skip, bool adaptive,
                       float s2) -> Variant& {
            Variant v;
            v.name = name;
            v.file = fileName(name);
            v.settings = base;
            v.settings.method = method;
            v.settings.skip = skip;
            v.settings.adaptive = adaptive;
            v.settings.maxStep = s2;
            v.s2Factor = adaptive ? s2 / s1 : 0.0;
            variants.push_back(v);
            return variants.back();
        };
        add("reference", RenderMethod::Reference, false, false, defaultS2);
        add("skipping only", RenderMethod::Partitions, true, false, defaultS2);
        add("adaptive only", RenderMethod::Partitions, false, true, defaultS2);
        add("skipping + adaptive", RenderMethod::Partitions, true, true, defaultS2);
        // Morrical et al. 2019 as published, for comparison: point samples, variance rule.
        add("reference, point", RenderMethod::Reference, false, false, defaultS2)
            .settings.preintegrated = false;
        Variant& paper =
            add("paper: variance, point", RenderMethod::Partitions, true, true, defaultS2);
        paper.settings.preintegrated = false;
        paper.settings.stepRule = StepRule::Variance;
        // The default: what --method auto renders this mesh with here (the row names it).
        add("auto", RenderMethod::Auto, true, true, base.maxStep);
        for (double f : *sweep) {
            char name[64];
            std::snprintf(name, sizeof name, "both, s2 = %g s1", f);
            Variant& v = add(name, RenderMethod::Partitions, true, true, float(f * s1));
            std::snprintf(name, sizeof name, "adaptive_s2-%g", f);
            v.file = name;
        }
        // The yardstick: one frame of the exact integrator (no sampling).
        ctx.step("rendering the exact image (the yardstick)");
        Variant exact;
        exact.name = "exact (1 frame)";
        exact.settings = base;
        exact.settings.method = RenderMethod::Exact;
        // On the GPU the first frame also loads the kernel (lazy module loading): time the
        // second.
        if (renderer.onGpu()) (void)renderer.render(exact.settings);
        exact.last = renderer.render(exact.settings);
        exact.medianSeconds = exact.last.stats.seconds;
        exact.samples = exact.last.stats.samples;  // tetrahedra crossed
        exact.cmp.ssim = 1.0;
        exact.cmp.psnr = INFINITY;
        const Rgb8Image yardstick = root ? toRgb8(exact.last.image, bg) : Rgb8Image{};
        if (root && !images->empty())
            writePng(*images + "/exact.png", exact.last.image, background);
        // Render: one warm-up frame, then `repeat` timed frames per variant.
        bool first = true;
        std::uint32_t heatmapMax = 0;  // the reference's largest count: one scale for all
        for (Variant& v : variants) {
            ctx.step("timing " + v.name);
            std::vector<double> times;
            v.last = renderer.render(v.settings);
            for (int r = 0; r < *repeat; ++r) {
                v.last = renderer.render(v.settings);
                times.push_back(v.last.stats.seconds);
            }
            v.medianSeconds = median(times);
            if (v.settings.method == RenderMethod::Auto)
                v.name = std::string("auto: ") + methodName(v.last.setup.method.method);
            v.samples = v.last.stats.samples;
            if (first)
                for (std::uint32_t c : v.last.sampleCounts) heatmapMax = std::max(heatmapMax, c);
            first = false;
            if (!root) continue;  // rank 0 holds the frames
            v.cmp = compareImages(yardstick, toRgb8(v.last.image, bg));
            if (!images->empty()) {
                const std::string stem = *images + "/" + v.file;
                writePng(stem + ".png", v.last.image, background);
                writePng(stem + "_samples.png", sampleHeatmap(v.last.sampleCounts, v.settings.width,
                                                              v.settings.height, heatmapMax));
            }
        }
        if (!root) return;
        // Table.
        const int threads = cpu::threadCount();
        char ruleBuf[64];
        if (base.stepRule == StepRule::ErrorBound)
            std::snprintf(ruleBuf, sizeof ruleBuf, "error (quality %g)", double(base.quality));
        else
            std::snprintf(ruleBuf, sizeof ruleBuf, "variance (p = %g)", double(base.power));
        const std::string ruleText = ruleBuf;
        const double refTime = variants.front().medianSeconds;
        // Samples per second per CPU core, or for the whole GPU.
        const std::string where =
            renderer.onGpu() ? cudaDeviceDescription() : std::to_string(threads) + " CPU thread(s)";
        const int units = renderer.onGpu() ? 1 : threads;
        std::printf(
            "%s: %s, %zu partitions (%.2f s to build), %dx%d, s1 = %g, "
            "step rule %s, %s, median of %d frames\n",
            printable(*file).c_str(), describeCells(prepared.tets).c_str(),
            prepared.kd->partitions.size(), prepared.kd->buildSeconds, base.width, base.height, s1,
            ruleText.c_str(), where.c_str(), *repeat);
        std::printf("%-22s %8s %10s %12s %9s %9s %8s %8s %6s %5s %5s\n", "configuration", "s2/s1",
                    "ms/frame", "samples", "spp", renderer.onGpu() ? "Msps" : "Msps/core",
                    "speed-up", "SSIM/exact", "p99.9", "max", "seams");
        std::vector<const Variant*> rows{&exact};  // exact's samples are tetrahedra crossed
        for (const Variant& v : variants) rows.push_back(&v);
        for (const Variant* row : rows) {
            const Variant& v = *row;
            const double pixels = double(base.width) * base.height;
            std::printf("%-22s %8s %10.2f %12llu %9.2f %9.1f %7.2fx %10.4f %6.1f %5g %5d\n",
                        v.name.c_str(),
                        v.s2Factor > 0 ? std::to_string(v.s2Factor).substr(0, 5).c_str() : "-",
                        v.medianSeconds * 1e3, static_cast<unsigned long long>(v.samples),
                        v.samples / pixels, v.samples / v.medianSeconds / units / 1e6,
                        refTime / v.medianSeconds, v.cmp.ssim, v.cmp.p999Difference,
                        v.cmp.maxAbsDifference, v.cmp.seamCount);
        }
        std::printf("transfer-function update: %.3f ms for %zu partitions\n",
                    variants.back().last.setup.tfUpdateSeconds * 1e3,
                    prepared.kd->partitions.size());
        const double seedSeconds = prepared.seeds ? prepared.seeds->buildSeconds : 0.0;
        std::printf(
            "preparation (%d CPU threads, BVHs and k-d tree on %s): split %.2f s, mesh BVH %.2f s, "
            "neighbours %.2f s, partitions %.2f s (k-d tree %.2f s), seed grids %.2f s\n",
            threads, prepared.builtElsewhere ? "the GPU" : "the CPU", prepared.splitSeconds,
            prepared.bvhSeconds, prepared.adjacencySeconds, prepared.kd->buildSeconds,
            prepared.kd->treeSeconds, seedSeconds);
        if (const std::optional<GpuResidency> gpu = renderer.gpuResidency()) {
            // The mesh BVH serves only the reference; `uvr render --method adaptive` leaves it out.
            // Per cell, and per tetrahedron of the split (comparable between native and split).
            const double cells = double(std::max<std::uint64_t>(1, prepared.tets.cellCount()));
            const double tets = double(std::max<std::uint64_t>(1, prepared.tets.splitTetCount()));
            const double all = double(gpu->geometryBytes);
            const double meshBvh = double(prepared.bvh.nodes.size() * sizeof(BvhNode) +
                                          prepared.bvh.primIds.size() * sizeof(std::uint32_t));
            std::printf(
                "device memory: %.2f GiB, %.1f bytes per cell, %.1f per tetrahedron of the "
                "split; without the mesh BVH (adaptive method alone) %.1f and %.1f\n",
                all / 1073741824.0, all / cells, all / tets, (all - meshBvh) / cells,
                (all - meshBvh) / tets);
        }
        // Files.
        if (!csv->empty())
            writeOutput(*csv, [&](OutputFile& csvFile) {
                std::ostringstream out;
                out << "configuration,s2_over_s1,seconds_per_frame,samples,samples_per_pixel,"
                       "speedup,ssim,psnr";
                for (const ComparisonField& f : differenceFields(ImageComparison{}))
                    out << ',' << f.name;
                out << '\n';
                for (const Variant* row : rows) {
                    const Variant& v = *row;
                    out << '"' << v.name << "\"," << v.s2Factor << ',' << v.medianSeconds << ','
                        << v.samples << ',' << v.samples / (double(base.width) * base.height) << ','
                        << refTime / v.medianSeconds << ',' << v.cmp.ssim << ',' << v.cmp.psnr;
                    for (const ComparisonField& f : differenceFields(v.cmp)) out << ',' << f.value;
                    out << '\n';
                }
                csvFile.write(out.str());
            });
        if (!json->empty())
            writeOutput(*json, [&](OutputFile& out) {
                nlohmann::json j;
                j["file"] = *file;
                j["field"] = field.name;
                j["field_association"] = associationName(field.association);
                j["tetrahedra"] = prepared.tets.tetCount();
                j["cells"] = prepared.tets.cellCount();
                j["split_tetrahedra"] = prepared.tets.splitTetCount();
                j["partitions"] = prepared.kd->partitions.size();
                j["partition_build_seconds"] = prepared.kd->buildSeconds;
                j["mesh_bvh_seconds"] = prepared.bvhSeconds;
                j["bvh_build_device"] = prepared.builtElsewhere ? "cuda" : "cpu";
                j["image"] = {base.width, base.height};
                j["supersample"] = base.supersample;  // samples per pixel sum its rays
                j["s1"] = s1;
                j["step_rule"] = stepRuleName(base.stepRule);
                j["quality"] = base.quality;
                j["power"] = base.power;
                j["sampling"] = samplingName(base.preintegrated);
                j["opacity_law"] = opacityLawName(base.opacityLaw);
                j["threads"] = threads;
                j["device"] = where;
                j["repeat"] = *repeat;
                j["ranks"] = ctx.comm ? ctx.comm->size() : 1;
                j["tf_update_seconds"] = variants.back().last.setup.tfUpdateSeconds;
                j["ssim_against"] = "exact";
                j["exact"] = {{"seconds_per_frame", exact.medianSeconds},
                              {"tetrahedra_crossed", exact.samples}};
                for (const Variant& v : variants) {
                    nlohmann::json row = {{"configuration", v.name},
                                          {"s2_over_s1", v.s2Factor},
                                          {"seconds_per_frame", v.medianSeconds},
                                          {"samples", v.samples},
                                          {"speedup", refTime / v.medianSeconds},
                                          {"ssim", v.cmp.ssim},
                                          {"psnr", v.cmp.psnr}};
                    for (const ComparisonField& f : differenceFields(v.cmp)) {
                        row[f.name] = f.integer ? nlohmann::json(static_cast<long long>(f.value))
                                                : nlohmann::json(f.value);
                    }
                    if (!images->empty()) row["image"] = v.file;  // <file>.png, <file>_samples.png
                    // Data-parallel: each rank's share of the last frame.
                    for (const RankFrameStats& r : v.last.ranks)
                        row["ranks"].push_back({{"frame_seconds", r.frameSeconds},
                                                {"composite_seconds", r.compositeSeconds},
                                                {"composite_bytes_sent", r.bytesSent},
                                                {"cells", r.cells}});
                    j["rows"].push_back(row);
                }
                // The heat maps' common scale and colours, for bench/plot_bench.py's legend.
                nlohmann::json ramp = nlohmann::json::array();
                for (int i = 0; i < 64; ++i) {
                    const Vec3f c = heatmapColor(float(i) / 63.f);
                    ramp.push_back({c.x, c.y, c.z});
                }
                j["heatmap"] = {{"max_samples", heatmapMax}, {"colors", ramp}};
                if (!images->empty()) j["images"] = *images;
                out.write(jsonText(j) + "\n");
            });
    });
}

}  // namespace uvr::cli

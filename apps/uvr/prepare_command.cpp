// SPDX-License-Identifier: MIT
// `uvr prepare`: reads a mesh, prepares it for rendering and writes a prepared cache that later
// renders read instead of the mesh (issue 16).
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli_common.h"
#include "progress.h"
#include "render_pipeline.h"

namespace uvr::cli {

namespace {

/// Lower-case extension of a path ("" for none).
std::string lowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

}  // namespace

void addPrepareCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "prepare",
        "Read a mesh, prepare it for rendering (cells, neighbours, partitions, BVHs, grids) and "
        "write a prepared cache (default MESH.uvrprep) that `uvr render MESH` then reads "
        "instead of the mesh");
    auto file = std::make_shared<std::string>();
    auto output = std::make_shared<std::string>();
    auto flags = std::make_shared<RenderFlags>();
    auto steps = std::make_shared<StepFlags>();
    cmd->add_option("FILE", *file, kMeshFileHelp)->required();
    cmd->add_option("-o,--output", *output, "The cache file to write (default: FILE.uvrprep)");
    cmd->add_option("--field", flags->field,
                    "Field to prepare, as `render --field` names it (default: the first scalar "
                    "field); a render uses the cache only with the same --field");
    flags->vocabulary.registerOnly(*cmd, {"method"});
    cmd->add_option("--leaf-cells", flags->leafCells,
                    "Adaptive: cells per k-d partition at most (default: the device's, as "
                    "render's)")
        ->check(CLI::Range(1u, 1u << 30));
    cmd->add_flag("--no-seed-grid", flags->noSeedGrid, "Adaptive: no seed grids (as render's)");
    cmd->add_flag("--split-cells", flags->splitCells,
                  "Split pyramids, wedges and hexahedra into tetrahedra (as render's)");
    cmd->add_option("--device", flags->device,
                    "Where the cache will render (it decides the default --leaf-cells): cpu, "
                    "cuda or auto")
        ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
        ->capture_default_str();
    cmd->add_option("--build-device", flags->buildDevice,
                    "Where the BVHs and k-d partitions are built: cpu, cuda or auto (as "
                    "render's)")
        ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
        ->capture_default_str();
    cmd->add_option("--threads", flags->threads, threadsHelp())->capture_default_str();
    steps->registerOn(*cmd);
    cmd->callback([file, output, flags, steps, &ctx] {
        applyThreads(flags->threads);
        // The key names one file: a series or a multi-file format would not see its other files
        // change.
        const std::string ext = lowerExtension(*file);
        if (isSeriesPattern(*file) || ext == ".pvd" || ext == ".pvtu")
            throwError(ErrorKind::Unsupported, *file,
                       "uvr prepare takes a single mesh file: a cache's key covers one file, "
                       "and this one names others (a series, .pvd or .pvtu)");
        flags->refuseIgnoredFlags();
        const std::string cache = output->empty() ? *file + kPreparedCacheSuffix : *output;
        checkOutputsDistinct({{"the input mesh", *file}}, {{"-o", cache}});
        // The default cache is a file beside the mesh: anything else there (a FIFO, a device)
        // is refused, not written into; -o may name one (the output conventions: written in
        // place, e.g. -o /dev/null to time the preparation).
        if (resolveOutput(cache).kind == OutputKind::Stream && output->empty())
            throwError(ErrorKind::Io, cache,
                       "the default prepared cache is not a regular file (a FIFO, socket or "
                       "device): remove it, or name it with -o to write there");
        const RendererOptions options = flags->rendererOptions();
        PrepareOptions prepareOptions = options.prepareOptions();
        // The key before the read: a mesh changed while it is read gives a stale cache.
        const CacheKey key = makeCacheKey(*file, flags->field, stepKey(*steps), prepareOptions);
        const CudaWarmUp cuda(flags->device);
        Mesh mesh = loadMesh(*file, ctx, *steps);
        const ScalarField field = selectScalarField(mesh, parseFieldSpec(flags->field));
        const auto start = std::chrono::steady_clock::now();
        const SourceSummary summary = checkForRendering(mesh, field, *file, ctx);
        ctx.setActivity(*file, "preparing the mesh for rendering");
        prepareOptions.afterSplit = [&mesh] { mesh = Mesh(); };  // not read once split
        PhaseProgress phases(ctx);
        const PreparedMesh prepared = prepareMesh(mesh, field, prepareOptions, phases.callbacks());
        phases.finish();
        ctx.done("prepared " + describeCells(prepared.tets) + " of " + field.describe(), start);
        ctx.setActivity(cache, "writing the prepared cache");
        std::uint64_t bytes = 0;
        {
            Progress progress(ctx, "writing " + cache);
            bytes = writePreparedCache(prepared, key, summary, cache, progress.callback());
            char line[200];
            std::snprintf(
                line, sizeof line, "wrote %s: %.1f MiB, %.1f bytes per cell", cache.c_str(),
                double(bytes) / 1048576.0,
                double(bytes) / double(std::max<std::uint64_t>(1, prepared.tets.cellCount())));
            progress.done(line);
        }
    });
}

}  // namespace uvr::cli

// SPDX-License-Identifier: MIT
#include "render_pipeline.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "progress.h"
#include "uvr/render/depth_image.h"

namespace uvr::cli {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

namespace {

/// Prints what was uploaded to the GPU, when the renderer renders there.
void reportUpload(const Renderer& renderer, const Context& ctx) {
    const std::optional<GpuResidency> gpu = renderer.gpuResidency();
    if (!gpu) return;
    char line[160];
    std::snprintf(line, sizeof line, "uploaded %.1f MiB to the GPU (%.1f bytes per cell) in %.3f s",
                  gpu->geometryBytes / 1048576.0,
                  double(gpu->geometryBytes) /
                      double(std::max<std::uint64_t>(1, renderer.prepared().tets.cellCount())),
                  gpu->uploadSeconds);
    ctx.step(line);
}

}  // namespace

std::unique_ptr<Renderer> makeRenderer(const Mesh& mesh, const ScalarField& field,
                                       const RendererOptions& options, const Context& ctx) {
    if (resolvesToCuda(options.device)) ctx.step("GPU: " + cudaDeviceDescription());
    PhaseProgress phases(ctx);
    auto renderer = std::make_unique<Renderer>(mesh, field, options, phases.callbacks());
    phases.finish();
    reportUpload(*renderer, ctx);
    return renderer;
}

namespace {

/// The settings of a render of `src`, checked; the camera fits the rendered cells (unused and
/// NaN/Inf points and flat cells left out).
RenderSettings checkedSettings(const RenderFlags& flags, const RenderSource& src,
                               const Context& ctx) {
    std::vector<std::string> notes;
    RenderSettings settings = flags.settings(src.summary.bounds, src.path, &notes);
    for (const std::string& note : notes) ctx.step("note: " + note);
    validateSettings(settings);
    return settings;
}

/// Renders a prepared mesh and writes the PNG, heat map and statistics: what a render from the
/// mesh and one from a prepared cache share.
RenderResult renderPreparedAndWrite(Renderer& renderer, const RenderSource& src,
                                    RenderSettings settings, const RenderOutputs& out,
                                    const Context& ctx) {
    const std::optional<Vec3f>& background = out.background;
    const std::string& source = src.path;
    const ScalarField field = src.summary.field();
    const PreparedMesh& prepared = renderer.prepared();
    const std::string title = legendTitle(field.name, field.association);
    LegendStyle style;
    style.background = background;
    if (out.legend && out.roomForLegend)  // the reset camera keeps the volume off the legend
        settings.camera =
            cameraBesideLegend(prepared, settings, src.summary.bounds, *out.legend, title);
    ctx.step("rendering " + field.describe() + (field.choice.empty() ? "" : ", " + field.choice) +
             " at " + std::to_string(settings.width) + "x" + std::to_string(settings.height) +
             (settings.supersample > 1
                  ? " with " + std::to_string(settings.supersample) + "x" +
                        std::to_string(settings.supersample) + " rays per pixel" +
                        (settings.jitter ? " (jittered)" : "")
                  : std::string()));
    ctx.setActivity(source, "rendering it at " + std::to_string(settings.width) + "x" +
                                std::to_string(settings.height));
    RenderResult result;
    {
        Progress progress(ctx, "rendering", double(settings.width) * settings.height, "pixels");
        settings.progress = progress.callback();
        result = renderer.render(settings);
        settings.progress = {};
    }
    if (!renderer.isRoot()) return result;  // rank 0 writes the frame (data-parallel)
    ctx.setActivity(out.image, "writing the image");
    char line[200];
    const std::string where = result.ranks.empty() ? std::string(renderer.deviceName())
                                                   : std::to_string(result.ranks.size()) +
                                                         " ranks (" + renderer.deviceName() + ")";
    std::snprintf(
        line, sizeof line, "rendered on %s in %.3f s: %llu samples, %.1f per pixel, step %g",
        where.c_str(), result.stats.seconds, static_cast<unsigned long long>(result.stats.samples),
        result.stats.meanSamplesPerPixel(), result.setup.params.step / result.setup.frame.scale);
    ctx.step(line);
    if (!result.setup.method.reason.empty()) ctx.step(result.setup.method.reason);
    if (result.setup.method.method == RenderMethod::Partitions) {
        std::snprintf(line, sizeof line,
                      "%zu partitions (built in %.3f s); transfer-function update %.3f ms; "
                      "%.1f partitions visited and %.1f skipped per pixel",
                      prepared.kd->partitions.size(), prepared.kd->buildSeconds,
                      result.setup.tfUpdateSeconds * 1e3,
                      double(result.stats.partitionsVisited) / (settings.width * settings.height),
                      double(result.stats.partitionsSkipped) / (settings.width * settings.height));
        ctx.step(line);
    }
    for (const std::string& note : result.setup.notes) ctx.warn(source + ": " + note);
    const std::string empty = explainEmptyFrame(prepared, settings, result);
    if (!empty.empty()) ctx.warn(source + ": " + empty);
    if (const std::optional<Font>& legendFont = out.legend) {
        drawLegend(result.image, *legendFont, settings.tf, result.setup.rangeLo,
                   result.setup.rangeHi, title, settings.tf.logScale, style);
        ctx.step("drew the legend in " + legendFont->familyName() + " (" + legendFont->path() +
                 ")");
    }
    // Every output is written first and committed after the last one succeeded: a failure (a
    // full disk) leaves none of them behind.
    std::vector<std::unique_ptr<OutputFile>> outputs;
    outputs.push_back(std::make_unique<OutputFile>(out.image));
    writePng(*outputs.back(), result.image, background);
    // The heat map's scale: --heatmap-max, else the frame's largest count (at least 1).
    std::uint32_t heatmapTop = out.heatmapMax.value_or(0);
    if (heatmapTop == 0)
        for (std::uint32_t c : result.sampleCounts) heatmapTop = std::max(heatmapTop, c);
    heatmapTop = std::max<std::uint32_t>(heatmapTop, 1);
    if (!out.heatmap.empty()) {
        ctx.setActivity(out.heatmap, "writing the heat map");
        outputs.push_back(std::make_unique<OutputFile>(out.heatmap));
        writePng(*outputs.back(),
                 sampleHeatmap(result.sampleCounts, settings.width, settings.height, heatmapTop));
        ctx.step("heat map: the bar runs from 0 samples per pixel (black, bottom) to " +
                 std::to_string(heatmapTop) + " (top)");
    }
    if (!out.depth.empty()) {
        ctx.setActivity(out.depth, "writing the depth image");
        outputs.push_back(std::make_unique<OutputFile>(out.depth));
        writeDepthNpy(*outputs.back(), settings.width, settings.height, result.depth);
    }
    if (!out.stats.empty()) {
        // The library's frame report, and what only the CLI knows: the file, its counts and
        // check, the prepared cache, the heat map's scale.
        nlohmann::json j = frameReport(renderer, settings, result);
        j["source"] = source;
        if (!out.heatmap.empty()) j["heatmap_max"] = heatmapTop;
        j["mesh"]["points"] = src.summary.points;
        j["mesh"]["cells"] = src.summary.cells;
        j["prepared_cache"] = {{"used", !src.cacheFile.empty()}};
        if (!src.cacheFile.empty()) {
            j["prepared_cache"]["file"] = src.cacheFile;
            j["prepared_cache"]["read_seconds"] = src.cacheReadSeconds;
        }
        j["prepare_seconds"]["check"] = src.checkSeconds;
        for (std::size_t r = 0; r < src.rankReadSeconds.size() && r < j["ranks"].size(); ++r)
            j["ranks"][r]["read_seconds"] = src.rankReadSeconds[r];
        outputs.push_back(std::make_unique<OutputFile>(out.stats));
        outputs.back()->write(jsonText(j) + "\n");
    }
    for (const auto& file : outputs) file->finish();  // buffered bytes reach the disk (or fail)
    for (const auto& file : outputs) {
        file->commit();
        // The image's background said (issue 35: a transparent PNG looks washed out on white).
        const bool transparentImage = file == outputs.front() && !background;
        ctx.step("wrote " + file->path() +
                 (transparentImage ? " (a transparent RGBA PNG: --background R,G,B composites it "
                                     "over a colour, as the viewer shows it over black)"
                                   : ""));
    }
    return result;
}

}  // namespace

RenderResult renderAndWrite(Mesh&& mesh, const std::string& source, const RenderFlags& flags,
                            const Context& ctx) {
    const RenderOutputs out = flags.renderOutputs();  // checked before the expensive work
    const ScalarField field = selectScalarField(mesh, parseFieldSpec(flags.field));
    const auto start = Clock::now();
    RenderSource src;
    src.path = source;
    src.summary = checkForRendering(mesh, field, source, ctx, &src.checkSeconds);
    // Every flag is parsed before the expensive preparation, so a bad flag fails fast.
    const RenderSettings settings = checkedSettings(flags, src, ctx);
    ctx.setActivity(source, "preparing the mesh for rendering");
    RendererOptions options = flags.rendererOptions();
    options.communicator = ctx.comm;
    // The mesh as read is not needed once split: freed then (a billion cells' arrays).
    options.afterSplit = [&mesh] { mesh = Mesh(); };
    const std::unique_ptr<Renderer> renderer = makeRenderer(mesh, field, options, ctx);
    ctx.done("prepared " + describeCells(renderer->prepared().tets), start);
    return renderPreparedAndWrite(*renderer, src, settings, out, ctx);
}

DistributedSource readDistributed(const std::string& file, const std::string& fieldSpec,
                                  const StepFlags& steps, const Context& ctx, bool keepFields) {
    Communicator& comm = *ctx.comm;
    const int rank = comm.rank(), ranks = comm.size();
    // This rank's part of the file.
    const auto readStart = Clock::now();
    std::optional<std::pair<std::uint64_t, std::uint64_t>> seriesParts;
    // Each rank reads whole pieces or partitions (ids: the piece above kPieceIdShift), not a run
    // of cells whose points the neighbouring runs share.
    bool byPieces = false;
    MeshPart part = agreeOn(comm, [&] {
        // A numbered series' pattern names no one file: its steps are read as a .pvd's.
        const MeshFormat format = isSeriesPattern(file) ? MeshFormat::Pvd : sniffMeshFormat(file);
        ReadOptions read;
        read.maxMemoryBytes = ctx.maxMemoryBytes;
        if (format == MeshFormat::Pvtu) {
            // A rank reads its run of the pieces when there are as many as ranks.
            const std::size_t pieceCount = pvtuPieceCount(file);
            if (pieceCount >= std::size_t(ranks)) {
                ctx.step("reading " + file + ": each of " + std::to_string(ranks) +
                         " ranks reads about " + std::to_string(pieceCount / ranks) + " of its " +
                         std::to_string(pieceCount) + " pieces");
                const auto [first, end] = rankRun(pieceCount, rank, ranks);
                byPieces = true;
                return readPvtuPart(file, first, end, read);
            }
            ctx.step("reading " + file + " whole on every rank: it has " +
                     std::to_string(pieceCount) + " pieces for " + std::to_string(ranks) +
                     " ranks");
        }
        if (format == MeshFormat::VtkHdf || format == MeshFormat::Exodus ||
            format == MeshFormat::Pvd) {
            // Stored in parts (a VTKHDF file's partitions, an Exodus file's cells, the pieces of
            // a collection's .pvtu step): a rank reads its run of them when there are as many as
            // ranks, the file opened once.
            const std::unique_ptr<MeshSeries> series = openSeries(file, ctx);
            const std::size_t step = steps.pick(*series);
            const std::uint64_t parts = series->partCount(step);
            const char* unit = series->partName();
            if (parts >= std::uint64_t(ranks)) {
                ctx.step("reading " + file + ": each of " + std::to_string(ranks) +
                         " ranks reads about " + std::to_string(parts / ranks) + " of its " +
                         std::to_string(parts) + " " + unit);
                seriesParts = rankRun(parts, rank, ranks);
                byPieces = format != MeshFormat::Exodus;
                return series->readPart(step, seriesParts->first, seriesParts->second);
            }
            ctx.step("reading " + file + " whole on every rank: " +
                     (parts ? "it has " + std::to_string(parts) + " " + unit + " for " +
                                  std::to_string(ranks) + " ranks"
                            : std::string("its time steps are not stored in pieces (.pvtu)")));
        }
        if (format == MeshFormat::Native && !steps.time && !steps.index) {
            const std::uint64_t n = readNativeSummary(file, false).cellCount;
            ctx.step("reading " + file + ": each of " + std::to_string(ranks) +
                     " ranks reads about " + std::to_string(n / ranks) + " of its " +
                     std::to_string(n) + " cells");
            const auto [first, end] = rankRun(n, rank, ranks);
            return readNativePart(file, first, end, read);
        }
        const Mesh whole = loadMesh(file, ctx, steps);
        const auto [first, end] = rankRun(whole.cellCount(), rank, ranks);
        return meshPart(whole, first, end);
    });
    const double readSeconds = std::chrono::duration<double>(Clock::now() - readStart).count();
    const std::uint64_t pointIdEnd = part.pointIds.empty() ? 0 : part.pointIds.back() + 1;
    const std::uint64_t pieceVertexCount = part.pointIds.size();
    DistributedSource out;
    out.seriesParts = seriesParts;
    out.source.rankReadSeconds = comm.allGatherValues(readSeconds);
    MeshShare& share = out.share;
    share = shareOfPart(comm, std::move(part), parseFieldSpec(fieldSpec), keepFields);
    // The checks, over every rank's share.
    RenderSource& src = out.source;
    src.path = file;
    // The whole file's points: every rank's pieces' points, or the highest id of a run's.
    std::uint64_t counts[2] = {share.mesh.cellCount(), byPieces ? pieceVertexCount : pointIdEnd};
    comm.allReduce(std::span<std::uint64_t>(counts, byPieces ? 2 : 1), ReduceOp::Sum);
    if (!byPieces) comm.allReduce(std::span<std::uint64_t>(counts + 1, 1), ReduceOp::Max);
    src.summary.cells = counts[0];
    src.summary.points = counts[1];
    src.summary.fieldName = share.field.name;
    src.summary.association = share.field.association;
    src.summary.fieldChoice = share.field.choice;
    src.summary.notes = share.mesh.notes;
    const SharesChecked checked = checkShares(share.mesh, file, ctx);
    src.summary.bounds = checked.bounds;
    src.summary.findings = checked.findings;
    if (src.summary.bounds.empty())
        throwError(ErrorKind::Validation, file,
                   "no cell has volume: all " + std::to_string(src.summary.cells) +
                       " cell(s) are flat or use NaN/Inf points; nothing to render");
    return out;
}

SharesChecked checkShares(const Mesh& share, const std::string& file, const Context& ctx) {
    Communicator& comm = *ctx.comm;
    const ValidationReport report = agreeOn(comm, [&] { return validateMesh(share, file); });
    SharesChecked out;
    out.bounds = reduceBounds(comm, report.bounds);
    std::string mine;
    for (const std::string& f : report.findings()) mine += f + "\n";
    const std::vector<std::vector<std::byte>> findings =
        comm.allGather(std::as_bytes(std::span<const char>(mine)));
    for (int r = 0; r < comm.size(); ++r) {
        const std::string text(reinterpret_cast<const char*>(findings[r].data()),
                               findings[r].size());
        for (std::size_t at = 0, end; (end = text.find('\n', at)) != std::string::npos;
             at = end + 1)
            out.findings.push_back(text.substr(at, end - at) + " (rank " + std::to_string(r) +
                                   "'s share)");
    }
    for (const std::string& f : out.findings) ctx.step("validation: " + f);
    return out;
}

RenderResult renderDataParallel(const std::string& file, const RenderFlags& flags,
                                const StepFlags& steps, const Context& ctx) {
    const RenderOutputs out = flags.renderOutputs();  // checked before the expensive work
    const auto start = Clock::now();
    DistributedSource read = readDistributed(file, flags.field, steps, ctx);
    const RenderSource& src = read.source;
    const int ranks = ctx.comm->size();
    const RenderSettings settings = checkedSettings(flags, src, ctx);
    ctx.setActivity(file, "preparing this rank's piece for rendering");
    RendererOptions options = flags.rendererOptions();
    options.communicator = ctx.comm;
    PhaseProgress phases(ctx);
    Renderer renderer(std::move(read.share), options, phases.callbacks());
    phases.finish();
    reportUpload(renderer, ctx);
    ctx.done("prepared " + std::to_string(ranks) +
                 " pieces; rank 0's: " + describeCells(renderer.prepared().tets),
             start);
    return renderPreparedAndWrite(renderer, src, settings, out, ctx);
}

void CacheFlags::registerOn(CLI::App& app) {
    auto* c = app.add_option("--cache", file,
                             "Render from this prepared cache (`uvr prepare`) without reading the "
                             "mesh; an error when it does not match the mesh and the flags "
                             "(default: MESH.uvrprep when it exists and matches)");
    auto* n = app.add_flag("--no-cache", off, "Ignore MESH.uvrprep: read and prepare the mesh");
    c->excludes(n);
}

std::unique_ptr<Renderer> makeRenderer(PreparedMesh prepared, Device device, const Context& ctx) {
    if (resolvesToCuda(device)) ctx.step("GPU: " + cudaDeviceDescription());
    auto renderer = std::make_unique<Renderer>(std::move(prepared), device);
    reportUpload(*renderer, ctx);
    return renderer;
}

void refuseCacheDataParallel(const CacheFlags& cache, const std::string& command) {
    if (!cache.file.empty())
        throwError(ErrorKind::Unsupported, "",
                   "--cache: a prepared cache is one process's preparation; a data-parallel " +
                       command + " (mpirun) prepares each rank's piece from the mesh");
}

std::optional<CacheMatch> findCache(const std::string& meshFile, const RenderFlags& flags,
                                    const StepFlags& steps, const CacheFlags& cache,
                                    const RendererOptions& options, bool anyMethods,
                                    RenderSource& src, const Context& ctx) {
    CacheMatch match;
    match.explicitCache = !cache.file.empty();
    if (cache.off) return std::nullopt;
    match.path = match.explicitCache ? cache.file : meshFile + kPreparedCacheSuffix;
    std::error_code ec;
    if (!match.explicitCache && (!std::filesystem::is_regular_file(match.path, ec) ||
                                 !std::filesystem::is_regular_file(meshFile, ec)))
        return std::nullopt;
    match.start = Clock::now();
    match.key = makeCacheKey(meshFile, flags.field, stepKey(steps), options.prepareOptions());
    src = RenderSource{};
    src.path = meshFile;
    src.cacheFile = match.path;
    try {
        const CacheHeader header = readPreparedCacheHeader(match.path);
        if (anyMethods) {
            // What the cache was prepared to render with is what the caller may offer.
            match.key.partitions = header.key.partitions;
            match.key.meshBvh = header.key.meshBvh;
            match.key.forAuto = header.key.forAuto;
            if (!match.key.forAuto) match.key.autoOnGpu = header.key.autoOnGpu;
        }
        const std::string why = cacheKeyMismatch(header.key, match.key);
        if (!why.empty()) throw StaleCacheError(match.path, why);
        src.summary = header.source;
    } catch (const Error& e) {
        if (match.explicitCache || e.kind() == ErrorKind::Resource) throw;
        ctx.warn(match.notUsing(e));
        return std::nullopt;
    }
    return match;
}

std::string CacheMatch::notUsing(const Error& e) const {
    const auto* stale = dynamic_cast<const StaleCacheError*>(&e);
    return "not using the prepared cache " + path + ": " +
           (stale ? stale->reason() : std::string(e.what())) +
           "; preparing from the mesh (`uvr prepare` renews the cache)";
}

std::optional<PreparedMesh> readCache(const CacheMatch& match, RenderSource& src,
                                      const Context& ctx) {
    // A default cache that is stale, damaged or not trusted (another user's, or writable by
    // others) is set aside with a warning saying why, and the mesh is prepared instead.
    ctx.setActivity(match.path, "reading the prepared cache");
    PreparedMesh prepared;
    try {
        LoadBudget budget(ctx.maxMemoryBytes);
        Progress progress(ctx, "reading the prepared cache " + match.path);
        prepared = readPreparedCache(match.path, match.key, budget, nullptr, progress.callback());
    } catch (const Error& e) {
        // Damage past the header (a truncated array, a failed CRC, a crafted index) sets a
        // default cache aside as header damage does; memory limits stay errors.
        if (match.explicitCache || e.kind() == ErrorKind::Resource) throw;
        ctx.warn(match.notUsing(e));
        return std::nullopt;
    }
    src.cacheReadSeconds = std::chrono::duration<double>(Clock::now() - match.start).count();
    char line[64];
    std::snprintf(line, sizeof line, " (read in %.3f s)", src.cacheReadSeconds);
    ctx.step("using the prepared cache " + match.path + line + ": " + describeCells(prepared.tets) +
             " prepared from " + src.path);
    for (const std::string& note : src.summary.notes) ctx.step("note: " + note);
    for (const std::string& f : src.summary.findings) ctx.step("validation: " + f);
    return prepared;
}

bool renderFromCache(const std::string& meshFile, const RenderFlags& flags, const StepFlags& steps,
                     const CacheFlags& cache, const Context& ctx) {
    const RendererOptions options = flags.rendererOptions();
    RenderSource src;
    const std::optional<CacheMatch> match =
        findCache(meshFile, flags, steps, cache, options, /*anyMethods=*/false, src, ctx);
    if (!match) return false;
    // The settings are checked before the arrays are read.
    const RenderOutputs out = flags.renderOutputs();
    const RenderSettings settings = checkedSettings(flags, src, ctx);
    std::optional<PreparedMesh> prepared = readCache(*match, src, ctx);
    if (!prepared) return false;
    ctx.setActivity(match->path, "uploading the prepared mesh");
    const std::unique_ptr<Renderer> renderer =
        makeRenderer(std::move(*prepared), options.device, ctx);
    renderPreparedAndWrite(*renderer, src, settings, out, ctx);
    return true;
}

}  // namespace uvr::cli

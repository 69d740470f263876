// SPDX-License-Identifier: MIT
// `uvr view`: reads and prepares a mesh once and serves it to browsers (src/uvr/server).
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>

#include "cli_common.h"
#include "progress.h"
#include "render_pipeline.h"

#ifdef UVR_HAS_SERVER
#include "uvr/server/view_server.h"
#endif

namespace uvr::cli {

namespace {

#ifdef UVR_HAS_SERVER
/// The flags that shape the image beyond what the page controls, for the page's exported
/// `uvr render` command (each a separate argument).
std::vector<std::string> imageFlags(const RenderFlags& f) {
    std::vector<std::string> out;
    auto add = [&](const char* flag, const std::string& value) {
        out.push_back(flag);
        if (!value.empty()) out.push_back(value);
    };
    // The settings the page has no control for, as given.
    for (const SettingDef& def : settingsVocabulary())
        if (f.vocabulary.given(def.name) && !server::isViewerSetting(def.name))
            add(cliFlag(def).c_str(), f.vocabulary.text(def.name));
    // The clip planes, isosurfaces and background are the page's (ViewState), the box the
    // command line's.
    if (!f.clipBox.empty()) add("--clip-box", f.clipBox);
    if (f.leafCells) add("--leaf-cells", std::to_string(f.leafCells));
    if (f.noSeedGrid) add("--no-seed-grid", "");
    if (f.splitCells) add("--split-cells", "");
    return out;
}

/// Every tab's starting state, as `uvr render` would draw the field (of finite range
/// fieldRange, over `cells` cells within scene.bounds) with these flags, and the scene's
/// settings beyond it.
void startingState(server::ViewScene& scene, const RenderSettings& settings,
                   const RenderFlags& flags, std::pair<float, float> fieldRange,
                   std::uint64_t cells) {
    server::ViewState& s = scene.initial;
    s.camera = settings.camera.value_or(
        resetCamera(scene.bounds, float(settings.width) / float(settings.height)));
    s.tf = settings.tf;
    s.range = settings.range.value_or(fieldRange);
    s.clipPlanes = settings.clipPlanes;
    s.isoSurfaces = settings.isoSurfaces;
    s.gradientOpacity = settings.gradientOpacity;
    s.field = flags.field;
    s.background = flags.backgroundColor().value_or(Vec3f(0.f, 0.f, 0.f));
    // The page's settings start as the command line set them (or their defaults), the opacity
    // unit ParaView's of the rendered cells' bounds.
    for (const char* name : server::kViewerSettings)
        s.settings[name] = settingNamed(name).get(settings);
    s.settings["opacity_unit"] =
        settings.opacityUnit > 0.f ? settings.opacityUnit : defaultOpacityUnit(scene.bounds, cells);
    s.width = settings.width;
    s.height = settings.height;
    scene.base = settings;
    scene.commandFlags = imageFlags(flags);
}

/// The scene of a prepared cache (`uvr prepare`, MESH.uvrprep or --cache) when one applies:
/// the mesh is not read, and the page shows the cache's field with the methods it holds.
/// Nothing when none applies (a default cache that is stale or damaged is set aside with a
/// warning, as `uvr render` does).
std::optional<server::ViewScene> sceneFromCache(const std::string& file, const RenderFlags& flags,
                                                const StepFlags& steps, const CacheFlags& cache,
                                                const Context& ctx) {
    RendererOptions options = flags.rendererOptions(true);
    options.partitions = options.meshBvh = true;
    RenderSource src;
    const std::optional<CacheMatch> match =
        findCache(file, flags, steps, cache, options, /*anyMethods=*/true, src, ctx);
    if (!match) return std::nullopt;
    // A series' time steps are read from the mesh (a cache holds one step).
    if (const std::size_t n = openSeries(file, ctx)->stepCount(); n > 1) {
        const std::string why = file + " has " + std::to_string(n) +
                                " time steps, which the viewer reads from the mesh (a prepared "
                                "cache holds one)";
        if (match->explicitCache) throwError(ErrorKind::Unsupported, "", "--cache: " + why);
        ctx.step("note: not using the prepared cache " + match->path + ": " + why);
        return std::nullopt;
    }
    std::vector<std::string> notes;
    const RenderSettings settings = flags.settings(src.summary.bounds, file, &notes);
    for (const std::string& note : notes) ctx.step("note: " + note);
    validateSettings(settings);
    std::optional<PreparedMesh> prepared = readCache(*match, src, ctx);
    if (!prepared) return std::nullopt;
    server::ViewScene scene;
    scene.file = file;
    scene.loadSeconds = src.cacheReadSeconds;
    scene.bounds = src.summary.bounds;
    for (const auto* lines : {&src.summary.findings, &src.summary.notes, &notes})
        scene.notes.insert(scene.notes.end(), lines->begin(), lines->end());
    ctx.setActivity(match->path, "uploading the prepared mesh");
    scene.renderer = makeRenderer(std::move(*prepared), options.device, ctx);
    const TetMesh& t = scene.renderer->prepared().tets;
    startingState(scene, settings, flags, {t.valueMin, t.valueMax}, src.summary.cells);
    scene.rendererOptions = options;
    scene.fromCache = server::ViewScene::FromCache{match->path, flags.field, src.summary};
    std::string methods;
    for (RenderMethod m : renderableMethods(scene.renderer->prepared()))
        methods += std::string(methods.empty() ? "" : ", ") + methodName(m);
    const std::string line = "serving the prepared cache's " + src.summary.field().describe() +
                             " alone (methods: " + methods +
                             "); --no-cache reads the mesh to show other fields";
    ctx.step(line);
    scene.notes.push_back(line);
    return scene;
}

/// The field spec that names `name` of `association` among `fields` ("name", or "name:cell"
/// where a point field has that name too): a series shows the field its first step chose at
/// every step.
std::string pinnedField(const std::vector<Field>& fields, const std::string& name,
                        Association association) {
    bool twoOfName = false;
    for (const Field& f : fields)
        twoOfName = twoOfName || (f.name == name && f.association != association);
    return name + (twoOfName && association == Association::Cell ? ":cell" : "");
}

/// Data-parallel, a file of one time step or a series stored in parts: each rank reads its part
/// of it as `uvr render` under mpirun does (readDistributed, keeping the part's fields for field
/// changes; a series' other steps by the same run of parts), and the server reduces what the
/// page lists over the ranks (ViewScene::part).
server::ViewScene sceneFromParts(const std::string& file, const RenderFlags& flags,
                                 const StepFlags& steps, const Context& ctx) {
    const auto start = std::chrono::steady_clock::now();
    DistributedSource read = readDistributed(file, flags.field, steps, ctx, /*keepFields=*/true);
    server::ViewScene scene;
    std::shared_ptr<MeshSeries> series = openSeries(file, ctx);
    scene.initial.step = steps.pick(*series);
    if (series->stepCount() > 1) {
        UVR_CHECK(read.seriesParts, "a series read by parts");
        scene.series = std::move(series);
    }
    scene.loadSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    scene.file = file;
    const SourceSummary& summary = read.source.summary;
    for (const auto* lines : {&summary.findings, &summary.notes})
        scene.notes.insert(scene.notes.end(), lines->begin(), lines->end());
    for (const std::string& n : summary.notes) ctx.step("note: " + n);
    std::vector<std::string> notes;
    const RenderSettings settings = flags.settings(summary.bounds, file, &notes);
    for (const std::string& note : notes) {
        ctx.step("note: " + note);
        scene.notes.push_back(note);
    }
    validateSettings(settings);
    scene.bounds = summary.bounds;
    startingState(scene, settings, flags, reduceFiniteRange(*ctx.comm, read.share.field.values),
                  summary.cells);
    if (scene.series && flags.field.empty())  // the field the ranks chose, at every step
        scene.initial.field = pinnedField(read.share.mesh.fields, read.share.field.name,
                                          read.share.field.association);
    scene.part =
        server::ViewScene::Part{std::move(read.share.pointIds), std::move(read.share.cellIds),
                                summary.points, summary.cells, read.seriesParts};
    scene.mesh = std::make_shared<Mesh>(std::move(read.share.mesh));
    scene.rendererOptions = flags.rendererOptions(true);
    scene.rendererOptions.partitions = scene.rendererOptions.meshBvh = true;
    scene.rendererOptions.communicator = ctx.comm;
    if (resolvesToCuda(scene.rendererOptions.device)) ctx.step("GPU: " + cudaDeviceDescription());
    return scene;
}

/// The scene of a mesh read and checked as `uvr render` does; the server prepares it (for
/// every method, the field switched without rebuilding geometry). Data-parallel, every rank
/// reads a series not stored in parts whole.
server::ViewScene sceneFromMesh(const std::string& file, const RenderFlags& flags,
                                const StepFlags& steps, const Context& ctx) {
    const auto start = std::chrono::steady_clock::now();
    auto mesh = std::make_shared<Mesh>(loadMesh(file, ctx, steps));
    server::ViewScene scene;
    std::shared_ptr<MeshSeries> series = openSeries(file, ctx);
    scene.initial.step = steps.pick(*series);
    if (series->stepCount() > 1) scene.series = std::move(series);
    scene.loadSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    scene.file = file;
    const ValidationReport report = validateMesh(*mesh, file);
    for (const std::string& f : report.findings()) {
        ctx.step("validation: " + f);
        scene.notes.push_back(f);
    }
    for (const std::string& n : mesh->notes) scene.notes.push_back(n);
    if (report.bounds.empty())
        throwError(ErrorKind::Validation, file,
                   "no cell has volume (or the mesh has no volumetric cells): nothing to view");
    const ScalarField field = selectScalarField(*mesh, parseFieldSpec(flags.field));
    std::vector<std::string> notes;
    RenderSettings settings = flags.settings(report.bounds, file, &notes);
    for (const std::string& note : notes) {
        ctx.step("note: " + note);
        scene.notes.push_back(note);
    }
    validateSettings(settings);
    scene.bounds = report.bounds;
    startingState(scene, settings, flags, finiteRange(field.values), mesh->cellCount());
    // A series shows one field at every step: the default its first step chose (pinField).
    if (scene.series && flags.field.empty()) {
        const FieldSpec pinned = pinField(*mesh, parseFieldSpec(""));
        scene.initial.field = pinnedField(mesh->fields, pinned.name, *pinned.association);
    }
    scene.mesh = mesh;
    // Every method can be picked in the page: the server prepares for all of them, in the
    // background once it listens, showing the steps in the log and the page.
    scene.rendererOptions = flags.rendererOptions(true);
    scene.rendererOptions.partitions = scene.rendererOptions.meshBvh = true;
    scene.rendererOptions.communicator = ctx.comm;  // under mpirun: each rank its piece
    if (resolvesToCuda(scene.rendererOptions.device)) ctx.step("GPU: " + cudaDeviceDescription());
    return scene;
}
#endif

}  // namespace

void addViewCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "view",
        "Explore a mesh in the browser: read and prepare it once (or read its prepared cache), "
        "then serve a page (printed URL "
        "with a token) to orbit, edit the transfer function and switch field, method and "
        "quality, rendered on the GPU or the CPU (docs/VIEWER.md)");
    auto file = std::make_shared<std::string>();
    auto flags = std::make_shared<RenderFlags>();
    auto options = std::make_shared<std::pair<std::string, int>>("127.0.0.1", 8080);
    auto token = std::make_shared<std::string>();
    auto steps = std::make_shared<StepFlags>();
    auto cache = std::make_shared<CacheFlags>();
    cmd->add_option("FILE", *file,
                    std::string(kMeshFileHelp) + ": the page gets a time slider for a series")
        ->required();
    flags->registerOn(*cmd, /*oneFrame=*/false, /*withMethod=*/true);
    steps->registerOn(*cmd);
    cache->registerOn(*cmd);
    cmd->add_option("--host", options->first,
                    "IP address to listen on (localhost is 127.0.0.1; 0.0.0.0: every interface, "
                    "the token still applies)")
        ->capture_default_str();
    cmd->add_option("--port", options->second, "Port to listen on (0: any free port)")
        ->check(CLI::Range(0, 65535))
        ->capture_default_str();
#ifdef UVR_HAS_SERVER  // the server's own limits (without it the command only says so)
    auto movingMs = std::make_shared<double>(server::ServerOptions{}.targetFrameMs);
    cmd->add_option("--moving-frame-ms", *movingMs,
                    "While the view moves, frames come at the reduced resolution that renders in "
                    "about this many milliseconds: 30 suits a GPU; on a CPU 50-100 gives sharper "
                    "moving frames at fewer updates")
        ->check(CLI::Range(server::kMinTargetFrameMs, server::kMaxTargetFrameMs))
        ->capture_default_str();
#endif
    cmd->add_option("--token", *token,
                    "The secret in the URL (default: 32 random hex characters; at least 16 of "
                    "A-Z a-z 0-9 _ -)");
    cmd->callback([=, &ctx] {
#ifndef UVR_HAS_SERVER
        throwError(ErrorKind::Unsupported, "",
                   "this uvr was built without the viewer's server (it needs libboost-dev and "
                   "libturbojpeg0-dev; see scripts/install-deps.sh)");
#else
        applyThreads(flags->threads);
        flags->checkBeforeLoading(*file);
        // The page's own limits on a side (one definition, the server's), before any reading.
        if (const auto [w, h] = parseSize("--size", flags->size);
            w < server::kMinViewSize || h < server::kMinViewSize || w > server::kMaxViewSize ||
            h > server::kMaxViewSize)
            throwError(ErrorKind::Argument, "",
                       "--size '" + flags->size + "': the viewer's sides are from " +
                           std::to_string(server::kMinViewSize) + " to " +
                           std::to_string(server::kMaxViewSize) +
                           " pixels (uvr render draws larger images)");
        checkFrameMemory(*flags, ctx);
        server::ServerOptions so;
        so.host = options->first;
        so.port = static_cast<std::uint16_t>(options->second);
        so.token = *token;
        so.targetFrameMs = *movingMs;
        // Before minutes of reading; rank 0 serves (data-parallel: the other ranks follow it).
        server::checkServerOptions(so, /*tryAddress=*/false);
        ctx.rootWrites([&] { server::checkServerOptions(so, /*tryAddress=*/true); });
        std::optional<server::ViewScene> chosen;  // from a prepared cache or the ranks' parts
        if (ctx.dataParallel()) {
            refuseCacheDataParallel(*cache, "view");
            // A file of one time step, or a series stored in as many parts as ranks, is read by
            // parts; another series whole on every rank.
            const std::unique_ptr<MeshSeries> series = openSeries(*file, ctx);
            if (series->stepCount() <= 1 ||
                series->partCount(steps->pick(*series)) >= std::uint64_t(ctx.comm->size()))
                chosen = sceneFromParts(*file, *flags, *steps, ctx);
            else
                ctx.step(
                    "reading the series whole on every rank: it is not stored in as many "
                    "parts as ranks");
        } else {
            chosen = sceneFromCache(*file, *flags, *steps, *cache, ctx);
        }
        server::ViewScene scene =
            chosen ? std::move(*chosen) : sceneFromMesh(*file, *flags, *steps, ctx);
        scene.sizeGiven = cmd->count("--size") > 0;
        // Serve until Ctrl-C.
        server::ViewServer server(std::move(scene), so, [&ctx](const std::string& line) {
            ctx.step(line.rfind("view: ", 0) == 0 ? line.substr(6) : line);
        });
        if (!ctx.root()) {
            // Data-parallel: this rank renders its piece of every frame rank 0's server asks
            // for, until it stops (mpirun's Ctrl-C reaches rank 0, which stops the others).
            std::signal(SIGINT, SIG_IGN);
            server.follow();
            return;
        }
        server.start();
        std::printf("uvr: serving %s (Ctrl-C stops)\n", server.url().c_str());
        std::fflush(stdout);
        server.run();
        ctx.step("stopped");
#endif
    });
}

}  // namespace uvr::cli

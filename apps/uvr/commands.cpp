// SPDX-License-Identifier: MIT
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "progress.h"
#include "render_pipeline.h"
#include "uvr/core/text.h"
#include "uvr/cpu/threads.h"

namespace uvr::cli {

namespace {

std::string fmt(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.7g", v);
    return buf;
}

void printCellCounts(std::uint64_t cells, const std::map<std::string, std::uint64_t>& byType) {
    std::printf("cells:   %llu", static_cast<unsigned long long>(cells));
    const char* sep = " (";
    for (const auto& [name, count] : byType) {
        std::printf("%s%s %llu", sep, name.c_str(), static_cast<unsigned long long>(count));
        sep = ", ";
    }
    std::printf("%s\n", byType.empty() ? "" : ")");
}

/// The fields as JSON, the default marked; ranges when the values were read.
nlohmann::json fieldsJson(const std::vector<FieldInfo>& fields, const Mesh* mesh) {
    const std::optional<std::size_t> def = defaultFieldIndex(fields);
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t i = 0; i < fields.size(); ++i) {
        const FieldInfo& f = fields[i];
        nlohmann::json j = {{"name", f.name},
                            {"association", associationName(f.association)},
                            {"components", f.components},
                            {"default", def == i}};
        if (mesh) {
            // By index, not by name: linear in the fields, and names may repeat.
            const ScalarField s = scalarFieldOf(*mesh, mesh->fields[i]);
            const auto [lo, hi] = finiteRange(s.values);
            j["range"] = {lo, hi};
        }
        out.push_back(std::move(j));
    }
    return out;
}

void printFields(const nlohmann::json& fields) {
    std::printf("fields:\n");
    if (fields.empty()) std::printf("  (none)\n");
    for (const auto& f : fields) {
        const int nc = f["components"];
        std::string line = "  " + printable(f["name"].get<std::string>());
        if (line.size() < 26) line.resize(26, ' ');
        char rest[160];
        std::snprintf(rest, sizeof rest, " %-5s %d component%s",
                      f["association"].get<std::string>().c_str(), nc, nc == 1 ? " " : "s");
        line += rest;
        if (f.contains("range"))
            line += std::string("  ") + (nc == 1 ? "" : "magnitude ") + "range [" +
                    fmt(f["range"][0].get<double>()) + ", " + fmt(f["range"][1].get<double>()) +
                    "]";
        if (f["default"].get<bool>()) line += "  (default)";
        std::printf("%s\n", line.c_str());
    }
}

/// Every time step of a file or series with more than one (none otherwise): index, time, its
/// file where each step has its own, whether its geometry is that of `mesh`, and each field's
/// finite range (of the magnitude for vectors).
nlohmann::json timeStepsJson(const std::string& path, const Mesh& mesh, const Context& ctx) {
    const std::unique_ptr<MeshSeries> series = openSeries(path, ctx);
    nlohmann::json out = nlohmann::json::array();
    if (series->stepCount() < 2) return out;
    Progress progress(
        ctx, "reading the ranges of " + std::to_string(series->stepCount()) + " time steps",
        double(series->stepCount()), "steps");
    for (std::size_t i = 0; i < series->stepCount(); ++i) {
        ctx.setActivity(series->stepSource(i), "reading time step " + std::to_string(i));
        std::optional<std::vector<Field>> fields = series->readFieldsIfSameGeometry(i, mesh);
        std::optional<Mesh> other;
        if (!fields) other = series->readStep(i);
        const MeshView geometry = other ? MeshView(*other) : MeshView(mesh);
        nlohmann::json ranges = nlohmann::json::array();
        for (const Field& f : fields ? *fields : other->fields) {
            const auto [lo, hi] = finiteRange(scalarFieldOf(geometry, f).values);
            ranges.push_back({{"name", f.name},
                              {"association", associationName(f.association)},
                              {"range", {lo, hi}}});
        }
        nlohmann::json step = {{"index", i},
                               {"time", series->times()[i]},
                               {"same_geometry", fields.has_value()},
                               {"fields", ranges}};
        if (series->stepSource(i) != path) step["source"] = series->stepSource(i);
        out.push_back(std::move(step));
        progress.set(double(i + 1) / double(series->stepCount()));
    }
    return out;
}

void printTimeSteps(const nlohmann::json& steps) {
    std::printf("time steps: %zu (time %s to %s)\n", steps.size(),
                fmt(steps.front()["time"].get<double>()).c_str(),
                fmt(steps.back()["time"].get<double>()).c_str());
    for (const auto& s : steps) {
        std::string line = "  " + std::to_string(s["index"].get<std::size_t>()) + "  time " +
                           fmt(s["time"].get<double>());
        if (!s["same_geometry"].get<bool>()) line += "  (other points or cells)";
        for (const auto& f : s["fields"])
            line += "  " + printable(f["name"].get<std::string>()) + " [" +
                    fmt(f["range"][0].get<double>()) + ", " + fmt(f["range"][1].get<double>()) +
                    "]";
        if (s.contains("source")) line += "  " + printable(s["source"].get<std::string>());
        std::printf("%s\n", line.c_str());
    }
}

/// Writes a mesh with a progress line; "wrote OUT" at the end.
void writeMeshWithProgress(const Mesh& mesh, const std::string& out, const Context& ctx,
                           const MeshWriteOptions& options = {}) {
    ctx.setActivity(out, "writing the mesh");
    Progress progress(ctx, "writing " + out);
    writeMesh(mesh, out, progress.callback(), options);
    progress.done("wrote " + out);
}

}  // namespace

/// Writes a time series as one file a step, OUT's name with _0000, _0001, ... before its
/// extension, and the ParaView .pvd beside them listing them (relative to its folder) at `times`;
/// stepMesh(k) gives step k's mesh, valid until the next call.
void writePvdSeries(const std::string& out, const std::vector<double>& times,
                    const std::function<const Mesh&(std::size_t)>& stepMesh, const Context& ctx,
                    const MeshWriteOptions& options = {}) {
    namespace fs = std::filesystem;
    const fs::path path(out);
    const std::string stem = path.stem().string(), ext = path.extension().string();
    std::string pvd =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" "
        "version=\"0.1\">\n  <Collection>\n";
    for (std::size_t k = 0; k < times.size(); ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "_%04zu", k);
        const std::string file = stem + name + ext;
        writeMeshWithProgress(stepMesh(k), (path.parent_path() / file).string(), ctx, options);
        pvd += "    <DataSet timestep=\"" + formatExact(times[k]) + "\" part=\"0\" file=\"" + file +
               "\"/>\n";
    }
    pvd += "  </Collection>\n</VTKFile>\n";
    const std::string pvdPath = (path.parent_path() / (stem + ".pvd")).string();
    OutputFile index(pvdPath);
    index.write(pvd);
    index.finish();
    index.commit();
    ctx.step("wrote " + pvdPath + " (" + std::to_string(times.size()) + " time steps)");
}

void addInfoCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "info",
        "Print counts, cell types, fields (the default marked), bounds, value ranges and "
        "validation findings; of a .uvrm only what its header holds unless --full");
    auto file = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    auto full = std::make_shared<bool>(false);
    auto steps = std::make_shared<StepFlags>();
    cmd->add_option("FILE", *file, kMeshFileHelp)->required();
    cmd->add_flag("--json", *json, "Print JSON instead of text");
    steps->registerOn(*cmd);
    cmd->add_flag("--full", *full,
                  "Of a .uvrm, also read the arrays for bounds, value ranges and validation "
                  "(other formats are always read whole)");
    cmd->callback([file, json, full, steps, &ctx] {
        // Of a .uvrm the header and the cell-type bytes: a 262M-tetrahedron file in a fraction
        // of a second instead of reading 8 GB.
        if (const std::optional<MeshSummary> header =
                *full || isSeriesPattern(*file) || steps->time || steps->index
                    ? std::nullopt
                    : readMeshSummary(*file)) {
            const MeshSummary& summary = *header;
            std::map<std::string, std::uint64_t> byType;
            for (const auto& [type, count] : summary.cellTypes) byType[cellTypeName(type)] = count;
            nlohmann::json j;
            j["file"] = *file;
            j["points"] = summary.pointCount;
            j["cells"] = summary.cellCount;
            j["cell_types"] = byType;
            j["fields"] = fieldsJson(summary.fields, nullptr);
            j["read"] = "header";
            if (*json) {
                std::printf("%s\n", jsonText(j).c_str());
                return;
            }
            std::printf("file:    %s\n", printable(*file).c_str());
            std::printf("points:  %llu\n", static_cast<unsigned long long>(summary.pointCount));
            printCellCounts(summary.cellCount, byType);
            printFields(j["fields"]);
            std::printf(
                "read the header only: bounds, value ranges and validation need --full (reads "
                "all %llu bytes)\n",
                static_cast<unsigned long long>(summary.fileBytes));
            return;
        }
        const Mesh mesh = loadMesh(*file, ctx, *steps);
        const nlohmann::json timeSteps = timeStepsJson(*file, mesh, ctx);
        ctx.step("validating " + *file);
        const ValidationReport report = validateMesh(mesh, *file);
        std::map<std::string, std::uint64_t> byType;
        for (CellType t : mesh.cellTypes) ++byType[cellTypeName(t)];
        const Bounds3f b = mesh.bounds();
        std::vector<FieldInfo> infos;
        for (const Field& f : mesh.fields) infos.push_back({f.name, f.association, f.components});
        nlohmann::json j;
        j["file"] = *file;
        j["points"] = mesh.pointCount();
        j["cells"] = mesh.cellCount();
        j["cell_types"] = byType;
        if (!b.empty()) j["bounds"] = {{b.lo.x, b.hi.x}, {b.lo.y, b.hi.y}, {b.lo.z, b.hi.z}};
        j["fields"] = fieldsJson(infos, &mesh);
        // Findings as objects (code, count, first, message) for scripts.
        std::vector<ValidationFinding> findings = report.structuredFindings();
        // Fields sharing a name and association are all listed; --field cannot tell them apart.
        std::map<std::pair<std::string, Association>, int> sameName;
        for (const Field& f : mesh.fields) ++sameName[{f.name, f.association}];
        for (const auto& [key, count] : sameName)
            if (count > 1)
                findings.push_back({"duplicate_field_names", static_cast<std::uint64_t>(count), "",
                                    0, key.first, "--field selects none of them",
                                    std::to_string(count) + " " + associationName(key.second) +
                                        " fields are named '" + key.first +
                                        "': --field selects none of them"});
        j["validation"] = nlohmann::json::array();
        for (const ValidationFinding& f : findings) {
            nlohmann::json o = {{"code", f.code}, {"count", f.count}, {"message", f.message}};
            if (!f.firstKind.empty()) o["first"] = {{f.firstKind, f.first}};
            if (!f.field.empty()) o["field"] = f.field;
            if (!f.action.empty()) o["action"] = f.action;
            j["validation"].push_back(std::move(o));
        }
        j["notes"] = mesh.notes;
        if (!timeSteps.empty()) j["time_steps"] = timeSteps;
        j["read"] = "whole file";
        if (*json) {
            std::printf("%s\n", jsonText(j).c_str());
            return;
        }
        // Names from the file are printed escaped (no control characters, valid UTF-8).
        std::printf("file:    %s\n", printable(*file).c_str());
        std::printf("points:  %llu\n", static_cast<unsigned long long>(mesh.pointCount()));
        printCellCounts(mesh.cellCount(), byType);
        if (!b.empty())
            std::printf("bounds:  x [%s, %s]  y [%s, %s]  z [%s, %s]\n", fmt(b.lo.x).c_str(),
                        fmt(b.hi.x).c_str(), fmt(b.lo.y).c_str(), fmt(b.hi.y).c_str(),
                        fmt(b.lo.z).c_str(), fmt(b.hi.z).c_str());
        printFields(j["fields"]);
        if (!timeSteps.empty()) printTimeSteps(timeSteps);
        std::printf("validation:\n");
        if (findings.empty()) std::printf("  no problems found\n");
        for (const ValidationFinding& f : findings)
            std::printf("  %s\n", printable(f.message).c_str());
        for (const std::string& s : mesh.notes) std::printf("note: %s\n", printable(s).c_str());
    });
}

void addRenderCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "render",
        "Render a mesh file to a PNG with the exact integrator where a ray crosses few cells and "
        "the adaptive partition method elsewhere (the default, --method auto), or the method "
        "--method names, on the CPU or a GPU");
    auto file = std::make_shared<std::string>();
    auto flags = std::make_shared<RenderFlags>();
    auto steps = std::make_shared<StepFlags>();
    auto cache = std::make_shared<CacheFlags>();
    cmd->add_option("FILE", *file, kMeshFileHelp)->required();
    flags->registerOn(*cmd);
    steps->registerOn(*cmd);
    cache->registerOn(*cmd);
    cmd->callback([file, flags, steps, cache, &ctx] {
        applyThreads(flags->threads);
        flags->checkFiles(*file);
        if (!cache->file.empty())
            checkOutputsDistinct({{"--cache", cache->file}}, flags->outputs());
        flags->checkBeforeLoading(*file);
        checkFrameMemory(*flags, ctx);
        const CudaWarmUp cuda(flags->device);  // CUDA starts while the mesh is read
        if (ctx.dataParallel()) {
            // Every rank reads its part of the file and prepares its piece; a prepared cache
            // holds one process's preparation.
            refuseCacheDataParallel(*cache, "render");
            renderDataParallel(*file, *flags, *steps, ctx);
            return;
        }
        if (renderFromCache(*file, *flags, *steps, *cache, ctx)) return;
        renderAndWrite(loadMesh(*file, ctx, *steps), *file, *flags, ctx);
    });
}

void addDemoCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "demo",
        "Generate the built-in procedural data set (a turbulent jet in a jittered "
        "tetrahedral box) and render it to a PNG");
    auto flags = std::make_shared<RenderFlags>();
    auto cells = std::make_shared<std::uint64_t>(400000);
    flags->output = "uvr-demo.png";
    flags->tf = "black-body";
    flags->opacity = "0:0,0.25:0.05,0.6:0.6,1:1";
    flags->background = "0.1,0.1,0.12";
    flags->azimuth = 30.f;
    flags->elevation = 15.f;
    flags->registerOn(*cmd);
    cmd->get_option("--output")->required(false)->capture_default_str();
    cmd->add_option("--cells", *cells, "Approximate tetrahedron count")
        ->capture_default_str()
        ->check(CLI::Range(std::uint64_t(1), std::uint64_t(2000000000)));
    cmd->callback([flags, cells, &ctx] {
        applyThreads(flags->threads);
        flags->checkFiles("");
        flags->checkBeforeLoading();
        ProceduralSpec spec;
        spec.shape = ProceduralShape::Box;
        spec.targetCells = *cells;
        checkFrameMemory(*flags, ctx);
        // The mesh, what rendering prepares from it and the frame, before generating anything.
        const std::uint64_t tets = proceduralTetCount(spec);
        checkMemoryEstimate(
            ctx,
            "--cells " + std::to_string(*cells) + " --size " + flags->size +
                ": generating, preparing and rendering " + std::to_string(tets) + " tetrahedra (" +
                std::to_string(proceduralMeshBytes(spec)) + " bytes for the mesh, " +
                std::to_string(kPrepareBytesPerTet) + " per tetrahedron to prepare it, " +
                std::to_string(frameMemoryBytes(*flags)) + " for the image)",
            proceduralMeshBytes(spec) + tets * kPrepareBytesPerTet + frameMemoryBytes(*flags));
        ctx.setActivity("", "generating the demo mesh");
        Progress progress(ctx,
                          "generating the demo mesh (" + std::to_string(*cells) + " tetrahedra)",
                          double(*cells), "tetrahedra");
        Mesh mesh = generateMesh(spec, progress.callback());
        progress.done("generated " + std::to_string(mesh.cellCount()) + " tetrahedra");
        renderAndWrite(std::move(mesh), "demo", *flags, ctx);
    });
}

void addConvertCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "convert",
        "Convert a mesh between formats (any readable format to .uvrm, .vtu, legacy .vtk or "
        ".vtkhdf); of a file or series with time steps, every step (one temporal .vtkhdf, or "
        "OUT_0000... and OUT.pvd) unless --time or --step-index picks one");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto compress = std::make_shared<std::string>();
    cmd->add_option("IN", *in, "Input mesh")->required();
    cmd->add_option("OUT", *out, "Output mesh (.uvrm native, .vtu, .vtk legacy binary or .vtkhdf)")
        ->required();
    cmd->add_option("--compress", *compress,
                    "Compression of a .vtu output: none, zlib (the default), lz4 (faster, larger) "
                    "or lzma (smaller, slower)")
        ->check(CLI::IsMember({"none", "zlib", "lz4", "lzma"}));
    auto steps = std::make_shared<StepFlags>();
    steps->registerOn(*cmd);
    cmd->callback([in, out, compress, steps, &ctx] {
        checkOutputsDistinct({{"the input mesh", *in}}, {{"OUT", *out}});
        resolveOutput(*out);
        MeshWriteOptions options;
        if (*compress == "none") options.compressor = VtuCompressor::None;
        if (*compress == "zlib") options.compressor = VtuCompressor::Zlib;
        if (*compress == "lz4") options.compressor = VtuCompressor::Lz4;
        if (*compress == "lzma") options.compressor = VtuCompressor::Lzma;
        checkMeshWritable(*out, options);  // before reading (minutes at 100M cells)
        const std::unique_ptr<MeshSeries> series = openSeries(*in, ctx);
        if (series->stepCount() == 1 || steps->time || steps->index) {
            const Mesh mesh = loadMesh(*in, ctx, *steps);
            return writeMeshWithProgress(mesh, *out, ctx, options);
        }
        // Every time step: one temporal .vtkhdf (one geometry), or a file a step and a .pvd.
        const std::vector<double>& times = series->times();
        ctx.step(*in + " has " + std::to_string(times.size()) +
                 " time steps: converting them all (--step-index or --time picks one)");
        Mesh mesh = loadMesh(*in, ctx, StepFlags{std::nullopt, 0});
        if (fileExtension(*out) == ".vtkhdf") {
            ctx.setActivity(*out, "writing the time series");
            Progress write(ctx, "writing " + *out);
            writeVtkHdfSeries(
                mesh, times,
                [&](std::size_t k) {
                    if (k == 0) return mesh.fields;
                    std::optional<std::vector<Field>> fields =
                        series->readFieldsIfSameGeometry(k, mesh);
                    if (!fields)
                        throwError(ErrorKind::Argument, *in,
                                   "time step " + std::to_string(k) +
                                       " has other points or cells than step 0, and a .vtkhdf "
                                       "series holds one geometry: give a .vtu, .vtk or .uvrm "
                                       "OUT (a file a step and a .pvd), or pick a step with "
                                       "--step-index or --time");
                    return std::move(*fields);
                },
                *out, write.callback());
            write.done("wrote " + *out + " (" + std::to_string(times.size()) + " time steps)");
            return;
        }
        writePvdSeries(
            *out, times,
            [&](std::size_t k) -> const Mesh& {
                if (k > 0) mesh = loadMesh(*in, ctx, StepFlags{std::nullopt, k});
                return mesh;
            },
            ctx, options);
    });
}

void addGenerateCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "generate",
        "Write a procedural mesh (a .uvrm is written slab by slab as it is generated, in a few "
        "hundred MB of memory whatever --cells)");
    auto shape = std::make_shared<std::string>("box");
    auto out = std::make_shared<std::string>();
    auto spec = std::make_shared<ProceduralSpec>();
    auto fields = std::make_shared<std::vector<std::string>>();
    cmd->add_option("SHAPE", *shape,
                    "box, shell (hollow, non-convex), graded (100x cell sizes), mixed "
                    "(hexahedra, wedges, pyramids and tetrahedra with every face pairing; its own "
                    "fields linear, xyz, block and cell_type; jitter 0.1 unless given, at most "
                    "0.15) or hex (mixed's grid with a hexahedron per block)")
        ->capture_default_str();
    cmd->add_option("-o,--output", *out, "Output mesh (.uvrm, .vtu, .vtk or .vtkhdf)")->required();
    cmd->add_option("--cells", spec->targetCells,
                    "Approximate cell count (tetrahedra; for mixed and hex, their cells)")
        ->capture_default_str()
        ->check(CLI::Range(std::uint64_t(1), std::uint64_t(4000000000)));
    cmd->add_option("--seed", spec->seed, "Random seed (same seed, same mesh)")
        ->capture_default_str();
    cmd->add_option("--jitter", spec->jitter, "Interior point jitter, fraction of the spacing")
        ->capture_default_str()
        ->check(CLI::Range(0.f, kMaxProceduralJitter));
    cmd->add_option(
           "--fields", *fields,
           "Fields to write, first is the default: jet, marschner_lobb, multiscale, linear, "
           "constant")
        ->delimiter(',');
    auto steps = std::make_shared<int>(1);
    auto dt = std::make_shared<double>(0.1);
    cmd->add_option("--steps", *steps,
                    "Time steps of one geometry, the fields turning about the y axis by --dt "
                    "radians a step: more than 1 writes one temporal file for a .vtkhdf OUT (the "
                    "geometry once), else OUT's name with _0000, _0001, ... before its extension, "
                    "a mesh a step, and a ParaView .pvd listing them")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--dt", *dt, "Time between steps (radians the fields turn)")
        ->capture_default_str()
        ->check(CLI::Range(-1e6, 1e6));
    cmd->callback([cmd, shape, out, spec, fields, steps, dt, &ctx] {
        const std::vector<std::string> shapes = {"box", "shell", "graded", "mixed", "hex"};
        if (std::find(shapes.begin(), shapes.end(), *shape) == shapes.end()) {
            const std::vector<std::string> close = closeMatches(*shape, shapes, 1);
            throwError(ErrorKind::Argument, "",
                       "unknown shape '" + *shape + "': expected box, shell, graded, mixed or hex" +
                           (close.empty() ? "" : " (did you mean " + close[0] + "?)"));
        }
        resolveOutput(*out);
        checkMeshWritable(*out);  // before generating
        if (*shape == "mixed" || *shape == "hex") {
            const bool hex = *shape == "hex";
            if (!fields->empty() || *steps != 1)
                throwError(ErrorKind::Argument, "",
                           "generate " + *shape +
                               " writes its own fields (linear, xyz, block, cell_type) and one "
                               "step: --fields and --steps do not apply");
            // Mixed: about 4.2 cells a block; at most 12 (a block of tetrahedra to its centre).
            const double perBlock = hex ? 1.0 : 4.2;
            const int n = static_cast<int>(
                std::clamp(std::round(std::cbrt(double(spec->targetCells) / perBlock)), 1.0,
                           double(kMaxMixedCellBlocks)));
            const std::uint64_t blocks = std::uint64_t(n) * n * n;
            const std::uint64_t points = std::uint64_t(n + 1) * (n + 1) * (n + 1) + blocks;
            checkMemoryEstimate(ctx,
                                "--cells " + std::to_string(spec->targetCells) + ": the mesh of " +
                                    std::to_string(n) + "^3 blocks",
                                points * 20 + blocks * 12 * (1 + 8 + 16 + 8));
            ctx.setActivity(*out, "generating the mesh");
            const float jitter = cmd->count("--jitter") ? spec->jitter : 0.1f;
            const Mesh mesh = generateMixedCellMesh(n, jitter, spec->seed, hex);
            ctx.step("generated " + std::to_string(mesh.pointCount()) + " points, " +
                     std::to_string(mesh.cellCount()) + " cells: " + mesh.notes.front());
            return writeMeshWithProgress(mesh, *out, ctx);
        }
        spec->shape = parseProceduralShape(*shape);
        if (!fields->empty()) {
            spec->fields.clear();
            for (const std::string& f : *fields) spec->fields.push_back(parseProceduralField(f));
        }
        // One .uvrm: written slab by slab as it is generated, never held whole.
        const bool stream = *steps == 1 && fileExtension(*out) == ".uvrm";
        checkMemoryEstimate(ctx,
                            "--cells " + std::to_string(spec->targetCells) + ": " +
                                (stream ? "the slabs of " : "the mesh of ") +
                                std::to_string(proceduralTetCount(*spec)) + " tetrahedra",
                            stream ? proceduralStreamBytes(*spec) : proceduralMeshBytes(*spec));
        ctx.setActivity(*out, "generating the mesh");
        if (stream) {
            Progress progress(ctx,
                              "generating " + std::string(proceduralShapeName(spec->shape)) +
                                  " with about " + std::to_string(spec->targetCells) +
                                  " tetrahedra into " + *out,
                              double(spec->targetCells), "tetrahedra");
            writeProceduralNative(*spec, *out, progress.callback());
            progress.done("wrote " + *out + " (" + std::to_string(proceduralTetCount(*spec)) +
                          " tetrahedra)");
            return;
        }
        Progress progress(ctx,
                          "generating " + std::string(proceduralShapeName(spec->shape)) +
                              " with about " + std::to_string(spec->targetCells) + " tetrahedra",
                          double(spec->targetCells), "tetrahedra");
        Mesh mesh = generateMesh(*spec, progress.callback());
        progress.done("generated " + std::to_string(mesh.pointCount()) + " points, " +
                      std::to_string(mesh.cellCount()) + " tetrahedra");
        if (*steps == 1) return writeMeshWithProgress(mesh, *out, ctx);
        if (fileExtension(*out) == ".vtkhdf") {
            // One temporal file: the geometry once, every step's fields.
            std::vector<double> times;
            for (int k = 0; k < *steps; ++k) times.push_back(*dt * k);
            ctx.setActivity(*out, "writing the time series");
            Progress write(ctx, "writing " + *out);
            writeVtkHdfSeries(
                mesh, times,
                [&](std::size_t k) {
                    ProceduralSpec at = *spec;
                    at.time = times[k];
                    Mesh stepMesh;
                    stepMesh.points = mesh.points;  // setProceduralFields reads the points only
                    setProceduralFields(stepMesh, at);
                    return std::move(stepMesh.fields);
                },
                *out, write.callback());
            write.done("wrote " + *out + " (" + std::to_string(*steps) +
                       " time steps of one geometry)");
            return;
        }
        // A time series: one file a step and the .pvd naming them.
        std::vector<double> times;
        for (int k = 0; k < *steps; ++k) times.push_back(*dt * k);
        writePvdSeries(
            *out, times,
            [&](std::size_t k) -> const Mesh& {
                ProceduralSpec at = *spec;
                at.time = times[k];
                if (k > 0) setProceduralFields(mesh, at);
                return mesh;
            },
            ctx);
    });
}

void addRefineCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "refine",
        "Split every tetrahedron into 8 at its edge midpoints, --levels times (non-tetrahedral "
        "cells are split into tetrahedra first); point fields are interpolated, cell fields "
        "copied; a .uvrm OUT is written as the last level is made, never held whole");
    auto in = std::make_shared<std::string>();
    auto out = std::make_shared<std::string>();
    auto levels = std::make_shared<int>(1);
    auto threads = std::make_shared<int>(0);
    cmd->add_option("IN", *in, "Input mesh")->required();
    cmd->add_option("OUT", *out, "Output mesh (.uvrm native, .vtu, .vtk legacy or .vtkhdf)")
        ->required();
    cmd->add_option("--levels", *levels, "Refinement levels (x8 tetrahedra each)")
        ->capture_default_str()
        ->check(CLI::Range(0, kMaxRefineLevels));
    cmd->add_option("--threads", *threads, threadsHelp())->capture_default_str();
    cmd->callback([in, out, levels, threads, &ctx] {
        applyThreads(*threads);
        checkOutputsDistinct({{"the input mesh", *in}}, {{"OUT", *out}});
        resolveOutput(*out);
        checkMeshWritable(*out);  // before the (possibly long) refinement
        const Mesh mesh = loadMesh(*in, ctx);
        // The whole refinement must fit --max-memory: the input, the output mesh and the work
        // arrays (estimate: hexahedra split into 6 tetrahedra, wedges and pyramids into 3).
        std::uint64_t tets = 0;
        for (CellType t : mesh.cellTypes)
            tets += t == CellType::Tetra ? 1 : (t == CellType::Hexahedron ? 6 : 3);
        const std::uint64_t outTets = refinedTetCount(tets, *levels);
        // A .uvrm output is written as the last level is made, never held whole.
        const bool stream = fileExtension(*out) == ".uvrm";
        const std::uint64_t bytes = refineMemoryBytes(mesh, tets, *levels, stream);
        checkMemoryEstimate(ctx,
                            *in + ": refining " + std::to_string(tets) + " tetrahedra " +
                                std::to_string(*levels) + " times (about " +
                                std::to_string(outTets) + " tetrahedra)",
                            bytes);
        ctx.setActivity(*in, "refining the mesh");
        if (stream) {
            Progress progress(ctx, "refining into " + *out, double(outTets), "tetrahedra");
            refineToNative(
                mesh, *levels, *out, [&](const std::string& s) { ctx.step(s); },
                progress.callback());
            progress.done("wrote " + *out + " (" + std::to_string(outTets) + " tetrahedra)");
            return;
        }
        Progress progress(ctx, "refining", double(outTets), "tetrahedra");
        const Mesh refined = refineMesh(
            mesh, *levels, [&](const std::string& s) { ctx.step(s); }, progress.callback());
        progress.done("refined to " + std::to_string(refined.pointCount()) + " points, " +
                      std::to_string(refined.cellCount()) + " tetrahedra");
        writeMeshWithProgress(refined, *out, ctx);
    });
}

void addPresetsCommand(CLI::App& app, Context& /*ctx*/) {
    auto* cmd = app.add_subcommand(
        "presets",
        "List the built-in colour maps (ParaView's presets, for --tf NAME) or the maps of a "
        "ParaView presets file (for --tf FILE.json:NAME): name, colour space, control points");
    auto file = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    cmd->add_option("FILE", *file,
                    "ParaView colour-map JSON (an export of one map or a presets file of many)");
    cmd->add_flag("--json", *json, "Print JSON instead of text");
    cmd->callback([file, json] {
        const std::vector<ColorMapInfo> maps =
            file->empty() ? transferFunctionPresets() : listParaViewColorMaps(*file);
        if (*json) {
            nlohmann::json j;
            j["source"] = file->empty() ? "built-in" : *file;
            j["colormaps"] = nlohmann::json::array();
            for (const ColorMapInfo& m : maps)
                j["colormaps"].push_back(
                    {{"name", m.name}, {"color_space", m.colorSpace}, {"points", m.points}});
            std::printf("%s\n", jsonText(j).c_str());
            return;
        }
        std::size_t width = 4;
        for (const ColorMapInfo& m : maps) width = std::max(width, printable(m.name).size());
        for (const ColorMapInfo& m : maps) {
            const std::string name = m.name.empty() ? "(unnamed)" : printable(m.name);
            const std::string points =
                m.points > 0 ? std::to_string(m.points) + " points" : "(not supported)";
            std::printf("%-*s  %-10s %s\n", static_cast<int>(width), name.c_str(),
                        printable(m.colorSpace).c_str(), points.c_str());
        }
        if (file->empty())
            std::printf(
                "%zu presets: --tf NAME (case, spaces, '-' and '_' do not matter; "
                "\"viridis\" for \"Viridis (matplotlib)\")\n",
                maps.size());
        else
            std::printf("%zu colour map%s: --tf %s:NAME\n", maps.size(),
                        maps.size() == 1 ? "" : "s", printable(*file).c_str());
    });
}

}  // namespace uvr::cli

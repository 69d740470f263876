// SPDX-License-Identifier: MIT
#pragma once

// The body of every fuzz target, shared by the libFuzzer entry points (fuzz_*.cpp) and the
// regression test that replays the kept inputs (fuzz_regression_test.cpp).

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "../apps/uvr/cli_common.h"
#include "byte_reader.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cpu/threads.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/io/vtk_legacy.h"
#include "uvr/mesh/io/vtkhdf.h"
#include "uvr/mesh/io/vtu.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/validate.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/image.h"
#include "uvr/tf/transfer_function.h"

#ifdef UVR_HAVE_NETCDF
#include "../tests/exodus_file_writer.h"
#include "uvr/mesh/io/exodus.h"
#endif
#ifdef UVR_HAS_HDF5
#include "fuzz_vtkhdf_input.h"
#endif

#ifdef UVR_HAS_SERVER
#include <nlohmann/json.hpp>

#include "uvr/server/view_state.h"
#endif

namespace uvr::fuzz {

/// Memory limit every fuzzed load runs under (the CLI's --max-memory), well below libFuzzer's
/// 2 GB RSS limit so that an allocation the limit misses is reported as a finding.
inline constexpr std::uint64_t kFuzzMaxMemory = 256ull << 20;

/// A folder private to this process (under TMPDIR or /tmp), removed at exit.
inline const std::string& scratchFolder() {
    static const std::string folder = [] {
        const char* base = std::getenv("TMPDIR");
        std::string pattern = std::string(base && *base ? base : "/tmp") + "/uvr_fuzz_XXXXXX";
        if (!::mkdtemp(pattern.data())) std::abort();
        static std::string removeAtExit;
        removeAtExit = pattern;
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(removeAtExit, ec);
        });
        return pattern;
    }();
    return folder;
}

/// Writes bytes to NAME in the scratch folder and returns the file's path.
inline std::string writeInput(const std::string& name, const std::uint8_t* data, std::size_t size) {
    const std::string path = scratchFolder() + "/" + name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path;
}

/// Read options of every fuzzed load.
inline ReadOptions fuzzReadOptions() {
    ReadOptions options;
    options.maxMemoryBytes = kFuzzMaxMemory;
    return options;
}

/// Runs f and swallows the library's documented failure, a uvr::Error, unless it reports a
/// broken invariant (ErrorKind::Internal: a bug), which propagates like any other exception.
/// Escaping exceptions, crashes and sanitizer reports are findings.
template <typename F>
void expectCleanError(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        if (e.kind() == ErrorKind::Internal) throw;
    }
}

/// What the CLI does with a mesh after loading it, short of rendering: full validation (cell
/// classification) and extraction of the default field.
inline void useMesh(const Mesh& mesh, const std::string& path) {
    (void)validateMesh(mesh, path);
    if (!mesh.fields.empty()) (void)selectScalarField(mesh, FieldSpec{});
}

/// Legacy VTK reader (ASCII and BINARY, versions 1.0 to 5.1).
inline void fuzzVtkLegacy(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput("input.vtk", data, size);
    expectCleanError([&] { useMesh(readVtkLegacy(path, fuzzReadOptions()), path); });
}

/// VTK XML .vtu reader (ascii, base64, appended raw/base64, zlib, header types, byte orders).
inline void fuzzVtu(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput("input.vtu", data, size);
    expectCleanError([&] { useMesh(readVtu(path, fuzzReadOptions()), path); });
}

/// Parallel .pvtu reader: the input is written as input.pvtu beside a small valid piece,
/// piece0.vtu (written once per process), so that inputs naming it reach the merge.
inline void fuzzPvtu(const std::uint8_t* data, std::size_t size) {
    static const bool pieceWritten = [] {
        ProceduralSpec spec;
        spec.targetCells = 200;
        spec.fields = {ProceduralField::Linear, ProceduralField::Constant};
        writeVtu(generateMesh(spec), scratchFolder() + "/piece0.vtu");
        return true;
    }();
    (void)pieceWritten;
    const std::string path = writeInput("input.pvtu", data, size);
    expectCleanError([&] { useMesh(readPvtu(path, fuzzReadOptions()), path); });
}

/// Time series: the input as a ParaView collection (input.pvd) beside a small valid step file,
/// step0.vtu (written once per process), so that inputs naming it reach the steps; every step
/// (the first four) is read whole and, after the first, through readFieldsIfSameGeometry.
inline void fuzzPvd(const std::uint8_t* data, std::size_t size) {
    static const bool stepWritten = [] {
        ProceduralSpec spec;
        spec.targetCells = 200;
        spec.fields = {ProceduralField::Linear};
        writeVtu(generateMesh(spec), scratchFolder() + "/step0.vtu");
        return true;
    }();
    (void)stepWritten;
    const std::string path = writeInput("input.pvd", data, size);
    expectCleanError([&] {
        const std::unique_ptr<MeshSeries> series = openMeshSeries(path, fuzzReadOptions());
        (void)stepAtTime(series->times(), 0.5);
        const Mesh first = series->readStep(0);
        useMesh(first, path);
        for (std::size_t i = 1; i < std::min<std::size_t>(series->stepCount(), 4); ++i)
            (void)series->readFieldsIfSameGeometry(i, first);
    });
}

/// Native .uvrm reader.
inline void fuzzNative(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput("input.uvrm", data, size);
    expectCleanError([&] { useMesh(readNative(path, fuzzReadOptions()), path); });
}

#ifdef UVR_HAS_HDF5
/// VTKHDF reader, structured: the bytes describe partitions, cells, offsets, fields and steps of
/// a file written through HDF5 (fuzz_vtkhdf_input.h); every step is read and handed to the
/// field-only path with the other steps.
inline void fuzzVtkHdf(const std::uint8_t* data, std::size_t size) {
    const std::vector<std::uint8_t> image = vtkHdfImage(data, size);
    const std::string path = writeInput("input.vtkhdf", image.data(), image.size());
    std::unique_ptr<MeshSeries> series;
    expectCleanError([&] { series = openVtkHdfSeries(path, fuzzReadOptions()); });
    for (std::size_t s = 0; series && s < series->stepCount() && s < 4; ++s) {
        expectCleanError([&] {
            const Mesh mesh = series->readStep(s);
            useMesh(mesh, path);
            for (std::size_t t = 0; t < series->stepCount() && t < 4; ++t)
                expectCleanError([&] { (void)series->readFieldsIfSameGeometry(t, mesh); });
        });
    }
}
#endif

/// ParaView colour-map JSON import, then the baked table.
inline void fuzzColormapJson(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput("input.json", data, size);
    expectCleanError([&] { (void)loadParaViewColorMap(path).bake(64); });
}

/// ParaView camera (.pvcc) loader, then camera validation and ray setup.
inline void fuzzPvcc(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput("input.pvcc", data, size);
    expectCleanError([&] {
        const Camera camera = loadPvcc(path);
        validateCamera(camera);
        (void)makeCameraRays(camera, 4, 3);
    });
}

/// The command line's text specs; the first byte picks the parser, the rest is the text:
/// --opacity (then the baked table), --field, --range, --size, a vector (--camera-position),
/// --max-memory, a --tf preset name.
inline void fuzzSpecs(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return;
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    expectCleanError([&] {
        switch (data[0] % 7) {
            case 0: {
                TransferFunction tf = transferFunctionPreset("viridis");
                applyOpacitySpec(tf, text);
                (void)tf.bake(64);
                break;
            }
            case 1:
                (void)parseFieldSpec(text);
                break;
            case 2:
                (void)cli::parseRange("--range", text);
                break;
            case 3:
                (void)cli::parseSize("--size", text);
                break;
            case 4:
                (void)cli::parseVec3("--camera-position", text);
                break;
            case 5:
                (void)cli::parseBytes("--max-memory", text);
                break;
            default:
                (void)transferFunctionPreset(text);
                break;
        }
    });
}

/// Most samples per ray the render target renders (a frame of 8x6 pixels under the sanitizers
/// stays well below a second); frames estimated above it are prepared and set up, not rendered.
inline constexpr double kFuzzMaxSamplesPerRay = 4000.0;

/// The whole render path on a tiny mesh with arbitrary values: 4 to 19 points (raw float
/// coordinates), 1 to 8 cells (tetrahedra, pyramids, wedges, hexahedra on any of the points), a
/// point or cell field of raw floats, then the method (reference, exact, three partition variants),
/// opacity, range, step and camera (the default or raw floats) of an 8x6 frame rendered on the CPU
/// and written as a PNG. Every finished frame must hold premultiplied pixels with alpha in [0, 1]
/// and no NaN. One CPU thread: parallel fuzzing processes would oversubscribe the cores.
inline void fuzzRender(const std::uint8_t* data, std::size_t size) {
    static const bool oneThread = (cpu::setThreadCount(1), true);
    (void)oneThread;
    ByteReader in(data, size);
    const std::uint8_t shape = in.byte(), cells = in.byte(), flags = in.byte(), view = in.byte();
    Mesh mesh;
    const int pointCount = 4 + shape % 16;
    for (int i = 0; i < pointCount; ++i) {
        const float x = in.real(), y = in.real(), z = in.real();
        mesh.points.emplace_back(x, y, z);
    }
    constexpr CellType kTypes[4] = {CellType::Tetra, CellType::Pyramid, CellType::Wedge,
                                    CellType::Hexahedron};
    const int cellCount = 1 + cells % 8;
    for (int c = 0; c < cellCount; ++c) {
        const CellType type = kTypes[in.byte() % 4];
        std::uint32_t ids[8];
        for (int k = 0; k < cornerCount(type); ++k) ids[k] = in.byte() % pointCount;
        mesh.addCell(type, std::span<const std::uint32_t>(ids, cornerCount(type)));
    }
    const bool cellField = flags & 1;
    std::vector<float> values(cellField ? cellCount : pointCount);
    for (float& v : values) v = in.real();
    mesh.fields.push_back({"f", cellField ? Association::Cell : Association::Point, 1, values});

    static const char* const kOpacities[4] = {"ramp", "step:0.5", "0:0,0.45:0,0.5:1,0.55:0,1:0",
                                              "constant:1"};
    RenderSettings settings;
    settings.width = 8;
    settings.height = 6;
    settings.tfTableSize = 64;
    settings.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(settings.tf, kOpacities[(flags >> 1) & 3]);
    const int method = (flags >> 3) & 3;
    settings.method = method != 0      ? RenderMethod::Partitions
                      : (shape & 0x10) ? RenderMethod::Exact
                                       : RenderMethod::Reference;
    settings.skip = method != 2;
    settings.adaptive = method != 3;
    if (flags & 0x20) settings.range = std::pair{in.real(), in.real()};
    if (flags & 0x40) settings.step = in.real();
    if (flags & 0x80) {
        Camera camera;
        camera.position = Vec3f(in.real(), in.real(), in.real());
        camera.focalPoint = Vec3f(in.real(), in.real(), in.real());
        camera.viewUp = Vec3f(in.real(), in.real(), in.real());
        camera.viewAngle = 0.01f + float(view % 179);
        settings.camera = camera;
    }
    expectCleanError([&] {
        (void)validateMesh(mesh, "fuzz");
        const ScalarField field = selectScalarField(mesh, FieldSpec{});
        PrepareOptions options;
        options.kd.leafCells = 2;  // several partitions from a handful of tetrahedra
        const PreparedMesh prepared = prepareMesh(mesh, field, options);
        const FrameSetup setup = makeFrameSetup(prepared, settings);
        if (!prepared.tets.tets.empty() &&
            prepared.tets.bounds.diagonal() / setup.params.step > kFuzzMaxSamplesPerRay)
            return;
        const RenderResult result = renderCpu(prepared, settings);
        for (const Vec4f& p : result.image.pixels)
            if (!(p.w >= 0.f && p.w <= 1.0001f) || !std::isfinite(p.x) || !std::isfinite(p.y) ||
                !std::isfinite(p.z)) {
                std::fprintf(stderr, "fuzzRender: pixel (%g, %g, %g, %g) out of range\n", p.x, p.y,
                             p.z, p.w);
                std::abort();
            }
        writePng(scratchFolder() + "/frame.png", result.image);
    });
}

#ifdef UVR_HAVE_NETCDF
/// Exodus II, structured: the bytes choose an Exodus file (layout flags, 0 to 23 nodes of raw float
/// coordinates, up to 4 blocks of any elem_type with any nodes per element and node numbers, nodal
/// and element variables with vector-like names, a truth table, up to 3 steps of raw values),
/// written through netCDF (so the reader, not netCDF's parser, is what is fuzzed) and read back
/// step by step: each step must load with consistent fields, or fail with a uvr::Error.
inline void fuzzExodus(const std::uint8_t* data, std::size_t size) {
    ByteReader in(data, size);
    testing::ExoFileSpec spec;
    const std::uint8_t shape = in.byte(), flags = in.byte();
    spec.combinedCoord = flags & 1;
    spec.combinedNodalVars = flags & 2;
    spec.doubles = flags & 4;
    spec.writeCoordinates = !(flags & 8);
    spec.numDim = (flags & 0x80) ? 2 : 3;
    const std::size_t nodes = shape % 24;
    for (std::size_t n = 0; n < nodes; ++n) {
        spec.x.push_back(in.real());
        spec.y.push_back(in.real());
        spec.z.push_back(in.real());
    }
    static const char* const kTypes[] = {"TETRA",    "TET4",  "tetra10", "HEX8",    "HEX",
                                         "HEX27",    "WEDGE", "WEDGE15", "PYRAMID", "PYRAMID13",
                                         "SHELL4",   "QUAD4", "TRI3",    "BAR2",    "NSIDED",
                                         "HEXSHELL", ""};
    static const std::size_t kNodes[] = {4, 4, 10, 8, 8, 27, 6, 15, 5, 13, 4, 4, 3, 2, 5, 12, 4};
    const int blocks = in.byte() % 5;
    for (int b = 0; b < blocks; ++b) {
        const std::uint8_t t = in.byte(), npe = in.byte(), elements = in.byte();
        testing::ExoBlock block;
        block.id = in.byte();
        block.elemType = kTypes[t % std::size(kTypes)];
        block.nodesPerElement = (npe & 0x80) ? npe % 30 : kNodes[t % std::size(kTypes)];
        for (std::size_t k = 0; k < block.nodesPerElement * (elements % 6); ++k)
            block.connect.push_back(in.byte() % (nodes + 3));  // 0 and past num_nodes too
        spec.blocks.push_back(block);
    }
    static const char* const kNames[] = {"T",     "VX",     "VY",     "VZ",     "vel_x", "vel_y",
                                         "vel_z", "DISPLX", "DISPLY", "DISPLZ", "",      "p"};
    for (int v = in.byte() % 5; v > 0; --v) spec.nodalVars.push_back(kNames[in.byte() % 12]);
    for (int v = in.byte() % 4; v > 0; --v) spec.elemVars.push_back(kNames[in.byte() % 12]);
    if (flags & 0x10)
        for (std::size_t k = 0; k < spec.blocks.size() * spec.elemVars.size(); ++k)
            spec.truthTable.push_back(in.byte() & 1);
    if (flags & 0x20) spec.firstNodalVarDim = "num_el_in_blk1";
    for (int s = in.byte() % 4; s > 0; --s) spec.times.push_back(in.real());
    spec.nodal = [&](std::size_t, std::size_t, std::size_t) { return in.real(); };
    spec.element = [&](std::size_t, std::size_t, std::size_t, std::size_t) { return in.real(); };
    const std::string path = scratchFolder() + "/input.e";
    try {
        testing::writeExodusFile(path, spec);
    } catch (const std::runtime_error&) {
        return;  // netCDF refused the layout (e.g. a variable on a dimension of no nodes)
    }
    expectCleanError([&] {
        auto series = openExodus(path, fuzzReadOptions());
        for (std::size_t s = 0; s < series->stepCount(); ++s) {
            const Mesh mesh = series->readStep(s);
            for (const Field& f : mesh.fields)
                if (f.values.size() !=
                    (f.association == Association::Point ? mesh.pointCount() : mesh.cellCount()) *
                        static_cast<std::size_t>(f.components)) {
                    std::fprintf(stderr, "fuzzExodus: field %s has %zu values\n", f.name.c_str(),
                                 f.values.size());
                    std::abort();
                }
            const auto fields = series->readFieldsIfSameGeometry(s, mesh);
            if (!fields || fields->size() != mesh.fields.size()) {
                std::fprintf(stderr, "fuzzExodus: the fields alone differ from the step's\n");
                std::abort();
            }
            useMesh(mesh, path);
        }
    });
}
#endif

#ifdef UVR_HAS_SERVER
/// A browser's `set` message to the viewer (docs/VIEWER.md): parsed as JSON, applied to a state
/// (all or nothing), then the state's frame settings validated and its exports written and read
/// back, as the server does with every message and `export`.
inline void fuzzViewMessage(const std::uint8_t* data, std::size_t size) {
    server::ViewState state;
    state.camera = resetCamera(Bounds3f{Vec3f(0.f), Vec3f(1.f)}, 1.f);
    state.tf = transferFunctionPreset("cool-to-warm");
    state.range = {0.f, 1.f};
    const server::ViewState before = state;
    nlohmann::json message;
    try {
        message = nlohmann::json::parse(data, data + size);
    } catch (const nlohmann::json::exception&) {
        return;  // the server answers malformed JSON with an error
    }
    bool applied = false;
    expectCleanError([&] {
        server::applySet(state, message);
        applied = true;
    });
    if (!applied && server::toJson(state) != server::toJson(before)) {
        std::fprintf(stderr, "fuzzViewMessage: a refused message changed the state\n");
        std::abort();
    }
    expectCleanError([&] {
        validateSettings(server::frameSettings(state, RenderSettings{}, 3));
        const std::string tf =
            paraViewColorMapJson(state.tf, state.range.first, state.range.second);
        (void)parseParaViewColorMap({tf.begin(), tf.end()}, "export").bake(64);
        const std::string pvcc = pvccText(state.camera);
        (void)parsePvcc({pvcc.begin(), pvcc.end()}, "export");
    });
}
#endif

/// A fuzz target: its name (the folder of its seeds and kept inputs) and its body.
struct FuzzTarget {
    const char* name;
    void (*run)(const std::uint8_t* data, std::size_t size);
};

/// Every fuzz target.
inline constexpr FuzzTarget kFuzzTargets[] = {
    {"vtk_legacy", fuzzVtkLegacy},
    {"vtu", fuzzVtu},
    {"pvtu", fuzzPvtu},
    {"pvd", fuzzPvd},
    {"native", fuzzNative},
    {"colormap_json", fuzzColormapJson},
    {"pvcc", fuzzPvcc},
    {"specs", fuzzSpecs},
    {"render", fuzzRender},
#ifdef UVR_HAVE_NETCDF
    {"exodus", fuzzExodus},
#endif
#ifdef UVR_HAS_HDF5
    {"vtkhdf", fuzzVtkHdf},
#endif
#ifdef UVR_HAS_SERVER
    {"view_message", fuzzViewMessage},
#endif
};

}  // namespace uvr::fuzz

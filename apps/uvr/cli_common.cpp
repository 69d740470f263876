// SPDX-License-Identifier: MIT
#include "cli_common.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "progress.h"
#include "uvr/core/host_memory.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"
#include "uvr/cpu/threads.h"

namespace uvr::cli {

namespace {

using Clock = std::chrono::steady_clock;

[[noreturn]] void badFlag(const std::string& flag, const std::string& text,
                          const std::string& what) {
    throwError(ErrorKind::Argument, "", flag + " '" + text + "': expected " + what);
}

bool parseFloat(std::string_view s, float& out) {
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, out);
    return ec == std::errc() && ptr == end && std::isfinite(out);
}

std::vector<float> parseFloats(const std::string& flag, const std::string& text, size_t count,
                               const std::string& what) {
    std::vector<float> out;
    size_t pos = 0;
    while (true) {
        size_t comma = text.find(',', pos);
        float v;
        if (!parseFloat(std::string_view(text).substr(
                            pos, comma == std::string::npos ? std::string::npos : comma - pos),
                        v))
            badFlag(flag, text, what);
        out.push_back(v);
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    if (out.size() != count) badFlag(flag, text, what);
    return out;
}

}  // namespace

namespace {

/// The long option `name` ("--max-step") of `app` or of one of its subcommands, or nullptr.
const CLI::Option* findFlag(const CLI::App& app, const std::string& name) {
    if (const CLI::Option* o = app.get_option_no_throw(name)) return o;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        if (const CLI::Option* o = findFlag(*sub, name)) return o;
    return nullptr;
}

}  // namespace

std::string Context::spell(const std::string& message) const {
    return respellMentions(message, [this](std::string_view setting) {
        std::string flag = "--" + std::string(setting);
        std::replace(flag.begin(), flag.end(), '_', '-');
        if (app && !findFlag(*app, flag) && findFlag(*app, "--no-" + flag.substr(2)))
            flag = "--no-" + flag.substr(2);
        return flag;
    });
}

std::string Context::spell(const Error& error) const {
    const auto* setting = dynamic_cast<const SettingError*>(&error);
    if (!setting) return spell(std::string(error.what()));
    const SettingDef* def = findSetting(setting->setting());
    return spell(
        setting->spelledAs(def ? cliFlag(*def) : spell("`" + setting->setting() + "`"), " "));
}

void Context::step(const std::string& message) const {
    if (!quiet) printStderrLine("uvr: " + printable(spell(message)));
}

void Context::warn(const std::string& message) const {
    printStderrLine("uvr: warning: " + printable(spell(message)));
}

void Context::done(const std::string& message, Clock::time_point start) const {
    if (quiet) return;
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, " (%.2f s)",
                  std::chrono::duration<double>(Clock::now() - start).count());
    printStderrLine("uvr: " + printable(message) + seconds);
}

void Context::setActivity(const std::string& file, const std::string& what) const {
    activityFile_ = file;
    activity_ = what;
}

std::string Context::outOfMemoryMessage() const {
    std::string m = activityFile_.empty() ? "" : activityFile_ + ": ";
    m += "out of memory";
    if (!activity_.empty()) m += " while " + activity_;
    return m;
}

std::string threadsHelp() {
    return "CPU threads: 1 to " + std::to_string(cpu::maxThreadCount()) +
           " (4 per hardware thread, at least 64, at most 1024), or 0 for the default: "
           "OMP_NUM_THREADS when set, else every hardware thread";
}

void applyThreads(int threads) {
    const int cap = cpu::maxThreadCount();
    if (threads < 0 || threads > cap)
        throwError(ErrorKind::Argument, "",
                   "--threads " + std::to_string(threads) + ": expected 1 to " +
                       std::to_string(cap) +
                       " (4 per hardware thread, at least 64, at most "
                       "1024), or 0 for the default");
    if (threads > 0) cpu::setThreadCount(threads);
}

void capEnvironmentThreads() {
    const int cap = cpu::maxThreadCount();
    if (cpu::threadCount() <= cap) return;
    const char* env = std::getenv("OMP_NUM_THREADS");
    std::fprintf(stderr, "uvr: note: OMP_NUM_THREADS=%s is more than %d threads; using %d\n",
                 env ? printableShort(env, 40).c_str() : "?", cap, cap);
    cpu::setThreadCount(cap);
}

std::string jsonText(const nlohmann::json& j) {
    return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::uint64_t parseBytes(const std::string& flag, const std::string& text) {
    std::uint64_t value = 0;
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    std::uint64_t scale = 1;
    if (ec == std::errc() && ptr + 1 == end) {
        switch (*ptr) {
            case 'K':
            case 'k':
                scale = 1ull << 10;
                break;
            case 'M':
            case 'm':
                scale = 1ull << 20;
                break;
            case 'G':
            case 'g':
                scale = 1ull << 30;
                break;
            case 'T':
            case 't':
                scale = 1ull << 40;
                break;
            default:
                scale = 0;
        }
        ++ptr;
    }
    if (ec != std::errc() || ptr != end || scale == 0 || value == 0 || value > (~0ull) / scale)
        badFlag(flag, text, "a positive byte count such as 500M or 16G");
    return value * scale;
}

MemoryDefault defaultMaxMemory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    const std::uint64_t sysconfBytes =
        pages > 0 && pageSize > 0
            ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageSize)
            : 0;
    const HostMemory host = detectHostMemory("/", sysconfBytes);
    if (host.bytes == 0) return {0, "no limit: the physical memory could not be read"};
    auto gib = [](std::uint64_t bytes) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / double(1ull << 30));
        return std::string(text);
    };
    const std::uint64_t bytes = host.bytes / 10 * 8;
    return {bytes, gib(bytes) + " = 80% of " + gib(host.bytes) + " (" + host.source + ")"};
}

Vec3f parseVec3(const std::string& flag, const std::string& text) {
    auto v = parseFloats(
        flag, text, 3,
        flag == "--background" ? "three finite numbers r,g,b" : "three finite numbers x,y,z");
    return {v[0], v[1], v[2]};
}

std::pair<float, float> parseRange(const std::string& flag, const std::string& text) {
    auto v = parseFloats(flag, text, 2, "two finite numbers lo,hi with lo <= hi");
    if (v[0] > v[1]) badFlag(flag, text, "two finite numbers lo,hi with lo <= hi");
    return {v[0], v[1]};
}

std::pair<int, int> parseSize(const std::string& flag, const std::string& text) {
    const size_t x = text.find_first_of("xX");
    int w = 0, h = 0;
    auto parseInt = [&](std::string_view s, int& out) {
        auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
        return ec == std::errc() && ptr == s.data() + s.size() && !s.empty();
    };
    if (x == std::string::npos || !parseInt(std::string_view(text).substr(0, x), w) ||
        !parseInt(std::string_view(text).substr(x + 1), h) || w < 1 || h < 1 || w > 16384 ||
        h > 16384)
        badFlag(flag, text, "WIDTHxHEIGHT with each side between 1 and 16384, e.g. 1024x768");
    return {w, h};
}

namespace {

/// A finite number above 0, with a plain message ("--step: must be a positive number, not 0")
/// instead of CLI11's range of all doubles.
CLI::Validator positiveNumber() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            double v = 0.0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
            if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) ||
                !(v > 0.0))
                return "must be a positive number, not " + text;
            return "";
        },
        "POSITIVE");
}

}  // namespace

void RenderFlags::registerOn(CLI::App& app, bool oneFrame, bool withMethod) {
    if (oneFrame)
        app.add_option("-o,--output", output,
                       "Output PNG file, or - for standard output (not a terminal)")
            ->required();
    app.add_option("--field", field,
                   "Field to render: NAME[:point|:cell][:magnitude|:x|:y|:z|:N] "
                   "(default: the first scalar field)");
    app.add_option("--tf", tf,
                   "Colour map: a ParaView preset by name (\"Cool to Warm\", viridis, Turbo, "
                   "Jet, \"Rainbow Uniform\", \"X Ray\", ...; `uvr presets` lists them), a "
                   "ParaView colour-map JSON export FILE.json, or one map of a presets file "
                   "FILE.json:NAME")
        ->capture_default_str();
    app.add_option("--opacity", opacity,
                   "Opacity: ramp, ramp:A, constant:A, step:T[:A] (binary) or x0:a0,x1:a1,... "
                   "over the normalised range (default: the JSON's Points, else ramp)")
        ->default_str(opacity.value_or(""));
    app.add_option("--range", range,
                   "Value range lo,hi the transfer function spans "
                   "(default: the field's range)");
    app.add_flag("--log", logScale,
                 "Map values to colours on a log scale, as ParaView's \"Use log scale when "
                 "mapping data to colors\" (also set by a JSON's UseLogScale); a range from 0 or "
                 "below starts at min(hi / 10^4, 1), as in ParaView");
    app.add_option("--nan-color", nanColor,
                   "Colour of NaN values r,g,b[,a] in [0, 1]; a is the opacity (default 1, "
                   "ParaView's NanOpacity). Without it NaN values take the colour map's NanColor "
                   "at opacity 0: invisible, unless a JSON's NanOpacity says otherwise");
    app.add_option("--size", size, "Image size WIDTHxHEIGHT")->capture_default_str();
    app.add_option("--camera", cameraFile, "ParaView camera file (.pvcc)");
    app.add_option("--camera-position", cameraPosition, "Camera position x,y,z");
    app.add_option("--camera-focal", cameraFocal, "Camera focal point x,y,z");
    app.add_option("--camera-up", cameraUp, "Camera view up x,y,z");
    app.add_option("--view-angle", viewAngle,
                   "Vertical view angle in degrees (default 30; perspective projection only)");
    app.add_flag("--parallel", parallel,
                 "Parallel (orthographic) projection, as ParaView's CameraParallelProjection: "
                 "every ray along the view direction, starting on the plane through the camera");
    app.add_option("--parallel-scale", parallelScale,
                   "With --parallel (or a parallel .pvcc): half the image height in world units, "
                   "as ParaView's CameraParallelScale (default: the camera file's, else the "
                   "bounding sphere's radius as ParaView's reset camera sets it)")
        ->check(positiveNumber());
    app.add_option("--azimuth", azimuth, "Rotate the camera about view up, degrees")
        ->capture_default_str();
    app.add_option("--elevation", elevation, "Rotate the camera about the right axis, degrees")
        ->capture_default_str();
    // The library's settings, each once (the vocabulary): its name, doc, default and check.
    std::vector<std::string> except;
    if (!withMethod) except.push_back("method");
    if (!oneFrame) except.insert(except.end(), {"skip", "adaptive"});
    vocabulary.registerOn(app, except);
    app.add_option("--leaf-cells", leafCells,
                   "Adaptive: cells per k-d partition at most (default " +
                       std::to_string(KdBuildOptions{}.leafCells) + " on the CPU, " +
                       std::to_string(kCudaDefaultLeafCells) + " with CUDA)")
        ->check(CLI::Range(1u, 1u << 30));
    app.add_flag(
        "--no-seed-grid", noSeedGrid,
        "Adaptive: no seed grids; long steps walk from the previous sample (GPU) or search "
        "the cell tree (CPU) (for comparisons)");
    app.add_flag("--split-cells", splitCells,
                 "Split pyramids, wedges and hexahedra into tetrahedra (linear on the split, "
                 "as ParaView's mappers do) instead of rendering them natively (trilinear "
                 "hexahedra); for comparisons");
    if (oneFrame) {
        app.add_option("--heatmap", heatmapFile,
                       "Also write the per-pixel sample counts as a heat map PNG");
        app.add_option("--heatmap-max", heatmapMax,
                       "Sample count at the top of the heat map scale (default: the frame's "
                       "maximum)");
    }
    app.add_option("--background", background,
                   "Composite over this colour r,g,b in [0,1] (default: transparent RGBA PNG)")
        ->capture_default_str();
    if (oneFrame)
        app.add_flag("--legend", legend,
                     "Draw a colour legend at the right edge: the field's name, the colour map "
                     "and tick values over the value range (needs --size of at least " +
                         std::to_string(kLegendMinWidth) + "x" + std::to_string(kLegendMinHeight) +
                         ")");
    if (oneFrame) app.add_option("--stats", statsFile, "Write render statistics to this JSON file");
    app.add_option("--device", device,
                   "Where to render: cpu, cuda, or auto (CUDA when a device is present)")
        ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
        ->capture_default_str();
    app.add_option("--build-device", buildDevice,
                   "Where the preparation builds: cpu (the CPU threads, binned SAH BVHs), cuda "
                   "(the GPU: linear BVHs, and the same k-d partitions, cell order, face "
                   "neighbours, seed grids and macrocells as the CPU's; seconds for 100M+ "
                   "tetrahedra), or auto (cuda when rendering on CUDA and the mesh has 4M "
                   "tetrahedra or more)")
        ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
        ->capture_default_str();
    app.add_option("--threads", threads, threadsHelp())->capture_default_str();
}

RenderSettings RenderFlags::baseSettings() const {
    RenderSettings s;
    std::tie(s.width, s.height) = parseSize("--size", size);
    s.tf = loadTransferFunction(tf);
    if (opacity) applyOpacitySpec(s.tf, *opacity);  // an empty spec is refused, not ignored
    if (logScale) s.tf.logScale = true;
    if (!nanColor.empty()) {
        const bool withAlpha = std::count(nanColor.begin(), nanColor.end(), ',') == 3;
        const auto v = parseFloats("--nan-color", nanColor, withAlpha ? 4 : 3,
                                   "r,g,b or r,g,b,a with numbers in [0, 1]");
        for (float c : v)
            if (!(c >= 0.f && c <= 1.f))
                badFlag("--nan-color", nanColor, "r,g,b or r,g,b,a with numbers in [0, 1]");
        s.tf.nanColor = Vec3f(v[0], v[1], v[2]);
        s.tf.nanOpacity = withAlpha ? v[3] : 1.f;
    }
    if (!range.empty()) s.range = parseRange("--range", range);
    // The settings of the library's vocabulary are checked there (main re-spells its errors
    // with the flags).
    vocabulary.applyTo(s);
    s.method = requestedMethod();
    refuseIgnoredFlags();
    if (s.stepRule == StepRule::Variance && vocabulary.given("quality"))
        throwError(ErrorKind::Argument, "",
                   "--quality sets the error rule's target: it needs "
                   "--step-rule error (the default), not variance");
    if (s.stepRule == StepRule::ErrorBound && vocabulary.given("power"))
        throwError(ErrorKind::Argument, "",
                   "--power shapes the variance rule's step: it needs --step-rule variance");
    if (heatmapMax && heatmapFile.empty())
        throwError(ErrorKind::Argument, "",
                   "--heatmap-max sets the heat map's scale: it needs --heatmap FILE.png");
    if (s.jitter && s.supersample < 2)
        throwError(ErrorKind::Argument, "",
                   "--jitter moves the rays of --supersample N inside the pixel: it needs "
                   "--supersample 2 or more");
    return s;
}

void RenderFlags::checkBeforeLoading(const std::string& meshFile) const {
    validateSettings(baseSettings());
    (void)backgroundColor();
    // What the camera needs of the mesh (its bounds) waits; its flags and file are read now.
    for (const auto& [flag, text] :
         {std::pair<const char*, const std::string&>{"--camera-position", cameraPosition},
          {"--camera-focal", cameraFocal},
          {"--camera-up", cameraUp}})
        if (!text.empty()) (void)parseVec3(flag, text);
    checkCameraFlags(!cameraFile.empty() && loadPvcc(cameraFile).parallelProjection);
    (void)legendFont();
    const FieldSpec spec = parseFieldSpec(field);
    // A .uvrm's header names its fields: a --field it lacks is refused before reading the arrays.
    if (!meshFile.empty() && !isSeriesPattern(meshFile))
        if (const std::optional<MeshSummary> header = readMeshSummary(meshFile, false))
            (void)resolveField(header->fields, spec);
}

void RenderFlags::checkCameraFlags(bool fileParallel) const {
    if (parallelScale && !parallel && !fileParallel)
        throwError(ErrorKind::Argument, "",
                   "--parallel-scale sets the half height of a parallel projection: it needs "
                   "--parallel (or a .pvcc with CameraParallelProjection 1)");
    if (viewAngle && (parallel || fileParallel))
        throwError(ErrorKind::Argument, "",
                   "--view-angle sets the perspective view angle, which parallel projection (" +
                       (parallel ? std::string("--parallel") : "the camera file " + cameraFile) +
                       ") does not have: use --parallel-scale for the half height of the view");
    if (viewAngle && !(*viewAngle >= kMinViewAngle && *viewAngle <= kMaxViewAngle)) {
        std::ostringstream os;
        os << "--view-angle " << *viewAngle << ": expected degrees in [" << kMinViewAngle << ", "
           << kMaxViewAngle << "]";
        throwError(ErrorKind::Argument, "", os.str());
    }
    if (!std::isfinite(azimuth) || !std::isfinite(elevation))
        throwError(ErrorKind::Argument, "", "--azimuth/--elevation must be finite");
}

RenderSettings RenderFlags::settings(const Bounds3f& bounds, const std::string& source,
                                     std::vector<std::string>* notes) const {
    RenderSettings s = baseSettings();
    // The camera file, else the default camera fitted to the bounds (its error names the mesh)
    // where camera flags leave its position or focal point to it; with no camera flag the
    // renderer resets the camera itself.
    Camera cam;
    bool custom = false;
    const bool placed = !cameraPosition.empty() && !cameraFocal.empty();
    const bool adjusted = !cameraPosition.empty() || !cameraFocal.empty() || !cameraUp.empty() ||
                          viewAngle || azimuth != 0.f || elevation != 0.f || parallel ||
                          parallelScale;
    const float aspect = float(s.width) / float(s.height);
    const auto reset = [&] {
        try {
            return resetCamera(bounds, aspect);
        } catch (const Error& e) {
            if (source.empty()) throw;
            throwError(e.kind(), source, e.what());
        }
    };
    bool fileScale = false;
    if (!cameraFile.empty()) {
        cam = loadPvcc(cameraFile, &fileScale), custom = true;
    } else if (adjusted && !placed) {
        cam = reset();
    }
    checkCameraFlags(!cameraFile.empty() && cam.parallelProjection);
    // Parallel projection: --parallel, or the camera file's. Its scale: --parallel-scale, else
    // the camera file's, else ParaView's reset value (the bounding sphere's radius).
    if (parallel) {
        if (!cam.parallelProjection && !fileScale && !parallelScale &&
            (placed || !cameraFile.empty()))
            cam.parallelScale = reset().parallelScale;
        cam.parallelProjection = true, custom = true;
    }
    if (parallelScale) cam.parallelScale = *parallelScale, custom = true;
    const bool fileUp = !cameraFile.empty() && cameraUp.empty();
    if (!cameraPosition.empty())
        cam.position = parseVec3("--camera-position", cameraPosition), custom = true;
    if (!cameraFocal.empty())
        cam.focalPoint = parseVec3("--camera-focal", cameraFocal), custom = true;
    if (!cameraUp.empty()) cam.viewUp = parseVec3("--camera-up", cameraUp), custom = true;
    // A view up parallel to the view direction cannot orient the image. The default one (+Y) is
    // replaced as ParaView's view-direction buttons do (+Z up when looking along Y); one the
    // user gave is refused with how to fix it.
    if (isFinite(cam.position) && isFinite(cam.focalPoint) && isFinite(cam.viewUp) &&
        cam.position != cam.focalPoint &&
        viewUpParallel(cam.position, cam.focalPoint, cam.viewUp)) {
        const Vec3f dir = normalize(cam.focalPoint - cam.position);
        std::ostringstream d;
        d << dir.x << "," << dir.y << "," << dir.z;
        if (cameraUp.empty() && !fileUp) {
            const Vec3f up = defaultViewUp(cam.position, cam.focalPoint);
            std::ostringstream u;
            u << up.x << "," << up.y << "," << up.z;
            if (notes)
                notes->push_back("the default view up 0,1,0 is parallel to the view direction " +
                                 d.str() + ": using --camera-up " + u.str() +
                                 " (give --camera-up to choose another)");
            cam.viewUp = up;
        } else {
            // Suggest the axis most across the view direction.
            const Vec3f axes[3] = {{0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}, {1.f, 0.f, 0.f}};
            const char* names[3] = {"0,1,0", "0,0,1", "1,0,0"};
            int best = 0;
            for (int k = 1; k < 3; ++k)
                if (std::fabs(dot(dir, axes[k])) < std::fabs(dot(dir, axes[best]))) best = k;
            std::ostringstream u;
            u << cam.viewUp.x << "," << cam.viewUp.y << "," << cam.viewUp.z;
            throwError(
                ErrorKind::Argument, fileUp ? cameraFile : "",
                (fileUp ? "view up " + u.str() + " (CameraViewUp)" : "--camera-up " + cameraUp) +
                    " is zero or parallel to the view direction " + d.str() +
                    ": pass a --camera-up across it, e.g. --camera-up " + names[best]);
        }
    }
    if (viewAngle) cam.viewAngle = *viewAngle, custom = true;
    validateCamera(cam);
    if (azimuth != 0.f || elevation != 0.f)
        cam = orbitCamera(cam, azimuth, elevation), custom = true;
    if (custom) s.camera = cam;
    return s;
}

std::optional<Font> RenderFlags::legendFont() const {
    if (!legend) return std::nullopt;
    const auto [width, height] = parseSize("--size", size);
    if (width < kLegendMinWidth || height < kLegendMinHeight)
        throwError(ErrorKind::Argument, "",
                   "--legend needs an image of at least " + std::to_string(kLegendMinWidth) + "x" +
                       std::to_string(kLegendMinHeight) + " pixels to be readable, not --size " +
                       size);
    try {
        return Font(findFontFile());
    } catch (const Error& e) {
        throwError(e.kind(), "", std::string("--legend: ") + e.what());
    }
}

std::optional<Vec3f> RenderFlags::backgroundColor() const {
    if (background.empty()) return std::nullopt;
    const Vec3f c = parseVec3("--background", background);
    for (int i = 0; i < 3; ++i)
        if (c[i] < 0.f || c[i] > 1.f)
            throwError(ErrorKind::Argument, "",
                       "--background '" + background + "': components must lie in [0,1]");
    return c;
}

std::vector<NamedFile> RenderFlags::outputs() const {
    std::vector<NamedFile> out;
    if (!output.empty()) out.push_back({"-o", output});
    if (!heatmapFile.empty()) out.push_back({"--heatmap", heatmapFile});
    if (!statsFile.empty()) out.push_back({"--stats", statsFile});
    return out;
}

std::vector<NamedFile> RenderFlags::inputs() const {
    const auto tfFile = splitColorMapFile(tf);  // FILE.json[:NAME]: the file
    std::vector<NamedFile> in{{"--tf", tfFile ? tfFile->first : tf}};
    if (!cameraFile.empty()) in.push_back({"--camera", cameraFile});
    return in;
}

namespace {

/// Refuses an output whose name does not say what is written (issue 15: `-o a.jpg` wrote PNG
/// bytes): its extension must be `ext` (any case). Standard output ("-") and existing files that
/// are not regular (/dev/null, FIFOs) are written whatever their names.
void checkExtension(const std::string& flag, const std::string& path, const std::string& ext,
                    const std::string& what) {
    if (path.empty() || path == "-") return;
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) return;
    std::string got = std::filesystem::path(path).extension().string();
    for (char& c : got) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (got == ext) return;
    throwError(ErrorKind::Argument, path,
               flag + " writes " + what + ": name it *" + ext + " (or - for standard output)");
}

}  // namespace

void RenderFlags::checkFiles(const std::string& meshFile) const {
    std::vector<NamedFile> in = inputs();
    if (!meshFile.empty()) in.push_back({"the input mesh", meshFile});
    checkOutputsDistinct(in, outputs());
    checkExtension("-o", output, ".png", "a PNG image");
    checkExtension("--heatmap", heatmapFile, ".png", "a PNG image");
    checkExtension("--stats", statsFile, ".json", "JSON");
    for (const NamedFile& out : outputs()) resolveOutput(out.path);
}

RenderMethod RenderFlags::requestedMethod() const {
    RenderSettings s;
    vocabulary.applyTo(s);
    if (s.method == RenderMethod::Auto && (tunesAdaptive(s) || leafCells || noSeedGrid))
        return RenderMethod::Partitions;
    return s.method;
}

void RenderFlags::refuseIgnoredFlags() const {
    const RenderMethod m = requestedMethod();
    std::vector<std::string> ignored;
    // The methods that read them, when they agree ("reference or adaptive").
    std::vector<RenderMethod> readers;
    bool agree = true;
    const auto note = [&](const std::string& flag, const std::vector<RenderMethod>& readBy) {
        if (ignored.empty()) readers = readBy;
        agree = agree && readers == readBy;
        ignored.push_back(flag);
    };
    for (const SettingDef* def : vocabulary.ignoredBy(m)) note(cliFlag(*def), def->readBy);
    if (m != RenderMethod::Partitions) {
        if (leafCells) note("--leaf-cells", {RenderMethod::Partitions});
        if (noSeedGrid) note("--no-seed-grid", {RenderMethod::Partitions});
    }
    if (ignored.empty()) return;
    std::string list, methods;
    for (std::size_t i = 0; i < ignored.size(); ++i)
        list += (i == 0 ? "" : i + 1 == ignored.size() ? " and " : ", ") + ignored[i];
    for (RenderMethod r : readers)
        methods += std::string(methods.empty() ? "" : " or ") + methodName(r);
    const bool one = ignored.size() == 1;
    throwError(ErrorKind::Argument, "",
               list + (one ? " is" : " are") + " not read by --method " + methodName(m) +
                   (agree ? std::string(one ? ": it needs" : ": they need") + " --method " + methods
                          : std::string(" (--help says which method reads each)")));
}

RendererOptions RenderFlags::rendererOptions(bool withReference) const {
    RendererOptions o;
    o.device = parseDevice(device, "--device");
    o.buildDevice = parseDevice(buildDevice, "--build-device");
    const RenderMethod m = requestedMethod();
    o.partitions = m == RenderMethod::Partitions;
    o.forAuto = m == RenderMethod::Auto;
    // The partition integrator uses its own BVHs.
    o.meshBvh = m == RenderMethod::Reference || m == RenderMethod::Exact || withReference;
    o.seedGrids = !noSeedGrid;
    o.splitCells = splitCells;
    o.leafCells = leafCells;
    return o;
}

CudaWarmUp::CudaWarmUp(const std::string& device) {
    if (device != "cpu") startCudaWarmUp();
}

CudaWarmUp::~CudaWarmUp() {
    finishCudaWarmUp();
}

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

void checkMemoryEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes) {
    if (ctx.maxMemoryBytes == 0 || bytes <= ctx.maxMemoryBytes) return;
    throwError(ErrorKind::Resource, "",
               what + " would need about " + std::to_string(bytes) +
                   " bytes, more than the --max-memory limit of " +
                   std::to_string(ctx.maxMemoryBytes) + " bytes" +
                   (ctx.maxMemoryDefault.empty() ? std::string()
                                                 : " (the default: " + ctx.maxMemoryDefault + ")"));
}

std::uint64_t frameMemoryBytes(const RenderFlags& flags, std::uint64_t frames) {
    const auto [width, height] = parseSize("--size", flags.size);
    const std::uint64_t w = static_cast<std::uint64_t>(std::max(width, 0));
    const std::uint64_t h = static_cast<std::uint64_t>(std::max(height, 0));
    std::uint64_t bytes = w * h * kFrameBytesPerPixel;
    if (!flags.heatmapFile.empty()) bytes += (w + kHeatmapLegendWidth) * h * kHeatmapBytesPerPixel;
    return frames * bytes;
}

void checkFrameEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes) {
    if (!ctx.maxMemoryDefault.empty() && bytes > kDefaultFrameMemoryBytes)
        throwError(ErrorKind::Resource, "",
                   what + " would need about " + std::to_string(bytes) +
                       " bytes, more than the default limit of image buffers, " +
                       std::to_string(kDefaultFrameMemoryBytes) + " bytes (" +
                       std::to_string(kDefaultFrameMemoryBytes >> 30) +
                       " GiB): give --max-memory to allow a larger frame (e.g. --max-memory " +
                       std::to_string((bytes >> 30) + 1) + "G)");
    checkMemoryEstimate(ctx, what, bytes);
}

void checkFrameMemory(const RenderFlags& flags, const Context& ctx) {
    checkFrameEstimate(
        ctx,
        "--size " + flags.size + ": the image buffers (" + std::to_string(kFrameBytesPerPixel) +
            " bytes per pixel" +
            (flags.heatmapFile.empty()
                 ? std::string()
                 : ", " + std::to_string(kHeatmapBytesPerPixel) + " more for the --heatmap") +
            ")",
        frameMemoryBytes(flags));
}

void StepFlags::registerOn(CLI::App& app) {
    auto* t = app.add_option("--time", time,
                             "Time step shown at this time (the last step at or before it, as "
                             "ParaView snaps) of a file or series with time steps");
    auto* i = app.add_option("--step-index", index,
                             "Time step by its index (0 is the first) of a file or series with "
                             "time steps");
    t->excludes(i);
}

std::size_t StepFlags::pick(const MeshSeries& series) const {
    if (time) return stepAtTime(series.times(), *time);
    if (index && *index >= series.stepCount())
        throwError(ErrorKind::Argument, series.path(),
                   "--step-index " + std::to_string(*index) + ": the file has " +
                       std::to_string(series.stepCount()) + " time step" +
                       (series.stepCount() == 1 ? "" : "s") + " (0 to " +
                       std::to_string(series.stepCount() - 1) + ")");
    return index.value_or(0);
}

std::unique_ptr<MeshSeries> openSeries(const std::string& path, const Context& ctx,
                                       std::function<void(double)> progress) {
    ReadOptions options;
    options.maxMemoryBytes = ctx.maxMemoryBytes;
    options.progress = std::move(progress);
    return openMeshSeries(path, options);
}

Mesh loadMesh(const std::string& path, const Context& ctx, const StepFlags& steps) {
    ctx.setActivity(path, "reading the mesh");
    Progress progress(ctx, "reading " + path);
    const std::unique_ptr<MeshSeries> series = openSeries(path, ctx, progress.callback());
    const std::size_t step = steps.pick(*series);
    Mesh mesh = series->readStep(step);  // every reader checks the structure it returns
    std::string which;
    if (series->stepCount() > 1) {
        char t[64];
        std::snprintf(t, sizeof t, "%.9g", series->times()[step]);
        which = ", time step " + std::to_string(step) + " of 0-" +
                std::to_string(series->stepCount() - 1) + " (time " + t + ")";
    }
    progress.done("read " + path + which + ": " + std::to_string(mesh.pointCount()) + " points, " +
                  std::to_string(mesh.cellCount()) + " cells");
    if (series->stepCount() > 1 && !steps.time && !steps.index)
        ctx.step("note: " + path + " has " + std::to_string(series->stepCount()) +
                 " time steps; --time or --step-index picks another, `uvr animate` renders all");
    for (const std::string& note : mesh.notes) ctx.step("note: " + note);
    return mesh;
}

SourceSummary checkForRendering(const Mesh& mesh, const ScalarField& field,
                                const std::string& source, const Context& ctx,
                                double* checkSeconds) {
    const auto start = Clock::now();
    ctx.step("checking " + std::to_string(mesh.cellCount()) + " cells and " +
             std::to_string(mesh.pointCount()) + " points");
    ValidationReport report;
    {
        Progress progress(ctx, "checking the mesh");
        report = validateMesh(mesh, source, progress.callback());
    }
    if (checkSeconds) *checkSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    ctx.done("checked the mesh", start);
    SourceSummary summary;
    summary.points = mesh.pointCount();
    summary.cells = mesh.cellCount();
    summary.bounds = report.bounds;
    summary.fieldName = field.name;
    summary.association = field.association;
    summary.fieldChoice = field.choice;
    summary.notes = mesh.notes;
    summary.findings = report.findings();
    for (const std::string& f : summary.findings) ctx.step("validation: " + f);
    if (report.bounds.empty())
        throwError(ErrorKind::Validation, source,
                   mesh.cellCount() == 0
                       ? "the mesh has no volumetric cells: nothing to render"
                       : "no cell has volume: all " + std::to_string(mesh.cellCount()) +
                             " cell(s) are flat (thinner than 1e-7 of their size) or use "
                             "NaN/Inf points; nothing to render");
    return summary;
}

std::string stepKey(const StepFlags& steps) {
    if (steps.time) {
        char t[40];
        std::snprintf(t, sizeof t, "--time %.17g", *steps.time);
        return t;
    }
    if (steps.index) return "--step-index " + std::to_string(*steps.index);
    return "";
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
                                    RenderSettings settings, const std::optional<Font>& legendFont,
                                    const RenderFlags& flags, const Context& ctx) {
    const std::optional<Vec3f> background = flags.backgroundColor();
    const std::string& source = src.path;
    const ScalarField field = src.summary.field();
    const PreparedMesh& prepared = renderer.prepared();
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
    ctx.setActivity(flags.output, "writing the image");
    char line[200];
    std::snprintf(
        line, sizeof line, "rendered on %s in %.3f s: %llu samples, %.1f per pixel, step %g",
        renderer.deviceName(), result.stats.seconds,
        static_cast<unsigned long long>(result.stats.samples), result.stats.meanSamplesPerPixel(),
        result.setup.params.step / result.setup.frame.scale);
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
    if (legendFont) {
        LegendStyle style;
        style.background = background;
        drawLegend(result.image, *legendFont, settings.tf, result.setup.rangeLo,
                   result.setup.rangeHi, field.name, settings.tf.logScale, style);
        ctx.step("drew the legend in " + legendFont->familyName() + " (" + legendFont->path() +
                 ")");
    }
    // Every output is written first and committed after the last one succeeded: a failure (a
    // full disk) leaves none of them behind.
    std::vector<std::unique_ptr<OutputFile>> outputs;
    outputs.push_back(std::make_unique<OutputFile>(flags.output));
    writePng(*outputs.back(), result.image, background);
    // The heat map's scale: --heatmap-max, else the frame's largest count (at least 1).
    std::uint32_t heatmapTop = flags.heatmapMax.value_or(0);
    if (heatmapTop == 0)
        for (std::uint32_t c : result.sampleCounts) heatmapTop = std::max(heatmapTop, c);
    heatmapTop = std::max<std::uint32_t>(heatmapTop, 1);
    if (!flags.heatmapFile.empty()) {
        ctx.setActivity(flags.heatmapFile, "writing the heat map");
        outputs.push_back(std::make_unique<OutputFile>(flags.heatmapFile));
        writePng(*outputs.back(),
                 sampleHeatmap(result.sampleCounts, settings.width, settings.height, heatmapTop));
        ctx.step("heat map: the bar runs from 0 samples per pixel (black, bottom) to " +
                 std::to_string(heatmapTop) + " (top)");
    }
    if (!flags.statsFile.empty()) {
        // The library's frame report, and what only the CLI knows: the file, its counts and
        // check, the prepared cache, the heat map's scale.
        nlohmann::json j = frameReport(renderer, settings, result);
        j["source"] = source;
        if (!flags.heatmapFile.empty()) j["heatmap_max"] = heatmapTop;
        j["mesh"]["points"] = src.summary.points;
        j["mesh"]["cells"] = src.summary.cells;
        j["prepared_cache"] = {{"used", !src.cacheFile.empty()}};
        if (!src.cacheFile.empty()) {
            j["prepared_cache"]["file"] = src.cacheFile;
            j["prepared_cache"]["read_seconds"] = src.cacheReadSeconds;
        }
        j["prepare_seconds"]["check"] = src.checkSeconds;
        outputs.push_back(std::make_unique<OutputFile>(flags.statsFile));
        outputs.back()->write(jsonText(j) + "\n");
    }
    for (const auto& out : outputs) out->finish();  // buffered bytes reach the disk (or fail)
    for (const auto& out : outputs) {
        out->commit();
        ctx.step("wrote " + out->path());
    }
    return result;
}

}  // namespace

RenderResult renderAndWrite(Mesh&& mesh, const std::string& source, const RenderFlags& flags,
                            const Context& ctx) {
    flags.backgroundColor();
    const std::optional<Font> legendFont = flags.legendFont();  // before the expensive work
    const ScalarField field = selectScalarField(mesh, parseFieldSpec(flags.field));
    const auto start = Clock::now();
    RenderSource src;
    src.path = source;
    src.summary = checkForRendering(mesh, field, source, ctx, &src.checkSeconds);
    // Every flag is parsed before the expensive preparation, so a bad flag fails fast.
    const RenderSettings settings = checkedSettings(flags, src, ctx);
    ctx.setActivity(source, "preparing the mesh for rendering");
    RendererOptions options = flags.rendererOptions();
    // The mesh as read is not needed once split: freed then (a billion cells' arrays).
    options.afterSplit = [&mesh] { mesh = Mesh(); };
    const std::unique_ptr<Renderer> renderer = makeRenderer(mesh, field, options, ctx);
    ctx.done("prepared " + describeCells(renderer->prepared().tets), start);
    return renderPreparedAndWrite(*renderer, src, settings, legendFont, flags, ctx);
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

bool renderFromCache(const std::string& meshFile, const RenderFlags& flags, const StepFlags& steps,
                     const CacheFlags& cache, const Context& ctx) {
    const bool explicitCache = !cache.file.empty();
    if (cache.off) return false;
    const std::string path = explicitCache ? cache.file : meshFile + kPreparedCacheSuffix;
    std::error_code ec;
    if (!explicitCache && (!std::filesystem::is_regular_file(path, ec) ||
                           !std::filesystem::is_regular_file(meshFile, ec)))
        return false;
    const auto start = Clock::now();
    const RendererOptions options = flags.rendererOptions();
    const CacheKey expected =
        makeCacheKey(meshFile, flags.field, stepKey(steps), options.prepareOptions());
    // A default cache that is stale, damaged or not trusted (another user's, or writable by
    // others) is set aside with a warning saying why, and the mesh is prepared instead.
    const auto notUsing = [&](const Error& e) {
        const auto* stale = dynamic_cast<const StaleCacheError*>(&e);
        return "not using the prepared cache " + path + ": " +
               (stale ? stale->reason() : std::string(e.what())) +
               "; preparing from the mesh (`uvr prepare` renews the cache)";
    };
    // The header first.
    RenderSource src;
    src.path = meshFile;
    src.cacheFile = path;
    PreparedMesh prepared;
    try {
        const CacheHeader header = readPreparedCacheHeader(path);
        const std::string why = cacheKeyMismatch(header.key, expected);
        if (!why.empty()) throw StaleCacheError(path, why);
        src.summary = header.source;
    } catch (const Error& e) {
        if (explicitCache || e.kind() == ErrorKind::Resource) throw;
        ctx.warn(notUsing(e));
        return false;
    }
    const std::optional<Font> legendFont = flags.legendFont();
    const RenderSettings settings = checkedSettings(flags, src, ctx);
    ctx.setActivity(path, "reading the prepared cache");
    try {
        LoadBudget budget(ctx.maxMemoryBytes);
        Progress progress(ctx, "reading the prepared cache " + path);
        prepared = readPreparedCache(path, expected, budget, nullptr, progress.callback());
    } catch (const Error& e) {
        // Damage past the header (a truncated array, a failed CRC, a crafted index) sets a
        // default cache aside as header damage does; memory limits stay errors.
        if (explicitCache || e.kind() == ErrorKind::Resource) throw;
        ctx.warn(notUsing(e));
        return false;
    }
    src.cacheReadSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    char line[64];
    std::snprintf(line, sizeof line, " (read in %.3f s)", src.cacheReadSeconds);
    ctx.step("using the prepared cache " + path + line + ": " + describeCells(prepared.tets) +
             " prepared from " + meshFile);
    for (const std::string& note : src.summary.notes) ctx.step("note: " + note);
    for (const std::string& f : src.summary.findings) ctx.step("validation: " + f);
    ctx.setActivity(path, "uploading the prepared mesh");
    const std::unique_ptr<Renderer> renderer =
        makeRenderer(std::move(prepared), options.device, ctx);
    renderPreparedAndWrite(*renderer, src, settings, legendFont, flags, ctx);
    return true;
}

}  // namespace uvr::cli

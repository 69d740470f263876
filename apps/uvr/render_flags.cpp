// SPDX-License-Identifier: MIT
#include "render_flags.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "uvr/core/setting_error.h"
#include "uvr/render/depth_image.h"

namespace uvr::cli {

namespace {

/// A finite number above 0, with a plain message ("--sample-distance: must be a positive number,
/// not 0") instead of CLI11's range of all doubles.
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
    app.add_option("--clip-plane,--clip-planes", clipPlanes,
                   "Clip the volume by a plane through ox,oy,oz with normal nx,ny,nz (file "
                   "coordinates): the side the normal points to is kept, every cell cut exactly "
                   "at the plane; repeat for up to " +
                       std::to_string(kMaxClipPlanes) + " planes")
        ->type_name("OX,OY,OZ,NX,NY,NZ")
        ->allow_extra_args(false)  // one value per occurrence: the mesh file may follow
        ->take_all();
    app.add_option("--clip-box", clipBox,
                   "Clip the volume to the box x0,y0,z0,x1,y1,z1 (file coordinates): only its "
                   "inside is kept")
        ->type_name("X0,Y0,Z0,X1,Y1,Z1");
    app.add_option("--iso", isoSurfaces,
                   "An isosurface inside the volume where the field equals VALUE, of opacity "
                   "OPACITY in (0, 1] (default 1: opaque) and colour #RRGGBB (default: the colour "
                   "map's at VALUE), lit by the headlight (--ambient, --diffuse, --specular, "
                   "--specular-power) and found exactly in every cell the ray crosses; repeat "
                   "for up to " +
                       std::to_string(kMaxIsoSurfaces) + " (a point field only)")
        ->type_name("VALUE[,OPACITY[,#RRGGBB]]")
        ->allow_extra_args(false)  // one value per occurrence: the mesh file may follow
        ->take_all();
    app.add_option("--gradient-opacity", gradientOpacity,
                   "Scale the opacity by the field gradient's magnitude, as VTK's gradient "
                   "opacity: a piecewise linear function through up to " +
                       std::to_string(kMaxGradientOpacityPoints) +
                       " points MAGNITUDE:SCALE (magnitudes in the field's units per file unit, "
                       "non-decreasing; scales in [0, 1]; constant beyond the ends), e.g. "
                       "0:0,0.5:1 fades regions flatter than 0.5 per unit; shaded or not "
                       "(--normals picks the gradients; a point field only)")
        ->type_name("MAGNITUDE:SCALE,...");
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
                   "Composite over this colour r,g,b in [0,1], e.g. 0,0,0 for black (default: a "
                   "transparent RGBA PNG, which image viewers show over white)")
        ->capture_default_str();
    if (oneFrame)
        app.add_flag("--legend", legend,
                     "Draw a colour legend at the right edge: the field's name, the colour map "
                     "and tick values over the value range; the reset camera moves the volume "
                     "off it (needs --size of at least " +
                         std::to_string(kLegendMinWidth) + "x" + std::to_string(kLegendMinHeight) +
                         ")");
    if (oneFrame) app.add_option("--stats", statsFile, "Write render statistics to this JSON file");
    if (oneFrame) {
        app.add_option("--depth", depthFile,
                       "Also write the depth image: per pixel the distance along the view "
                       "direction (file units) at which the accumulated opacity first reaches "
                       "--depth-opacity (an opaque --iso surface: the surface), inf where it "
                       "never does; a float32 NumPy .npy of shape (height, width), row 0 at the "
                       "top");
        app.add_option("--depth-opacity", depthOpacity,
                       "With --depth: the accumulated opacity whose depth is written (default 0.5)")
            ->check(CLI::Range(0.0001f, 1.f));
        app.add_option("--depth-in", depthInFile,
                       "Composite over opaque geometry rendered elsewhere: a .npy of shape "
                       "(height, width), float32 or float64, of its distances along the view "
                       "direction (file units, as --depth writes them; inf or NaN: none); every "
                       "ray of a pixel ends there");
    }
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
    for (const std::string& text : clipPlanes) {
        const std::vector<float> v = parseFloats("--clip-plane", text, 6,
                                                 "ox,oy,oz,nx,ny,nz: a point of the plane and its "
                                                 "normal, six finite numbers");
        s.clipPlanes.push_back({Vec3f(v[0], v[1], v[2]), Vec3f(v[3], v[4], v[5])});
    }
    if (!clipBox.empty()) {
        const std::vector<float> v =
            parseFloats("--clip-box", clipBox, 6, "x0,y0,z0,x1,y1,z1: six finite numbers");
        s.clipBox = Bounds3f{Vec3f(v[0], v[1], v[2]), Vec3f(v[3], v[4], v[5])};
    }
    for (const std::string& text : isoSurfaces) s.isoSurfaces.push_back(parseIsoSurface(text));
    if (gradientOpacity) s.gradientOpacity = parseGradientOpacity(*gradientOpacity);
    if (!depthFile.empty()) s.depthAlpha = depthOpacity.value_or(0.5f);
    if (!depthInFile.empty()) s.depthIn = readDepthNpy(depthInFile, s.width, s.height);
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
    if (depthOpacity && depthFile.empty())
        throwError(ErrorKind::Argument, "",
                   "--depth-opacity sets what --depth writes: it needs --depth FILE.npy");
    if (heatmapMax && heatmapFile.empty())
        throwError(ErrorKind::Argument, "",
                   "--heatmap-max sets the heat map's scale: it needs --heatmap FILE.png");
    std::vector<std::string> given;
    for (const SettingDef& def : settingsVocabulary())
        if (vocabulary.given(def.name)) given.emplace_back(def.name);
    try {
        refuseUnreadSettings(s, given);
    } catch (const SettingError& e) {  // quoting the value as typed ("8", not "8.0")
        throw SettingError(e.setting(), vocabulary.text(e.setting()), e.expected());
    }
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
    return annotationFont("--legend", "an image");
}

Font RenderFlags::annotationFont(const std::string& flag, const std::string& image) const {
    const auto [width, height] = parseSize("--size", size);
    if (width < kLegendMinWidth || height < kLegendMinHeight)
        throwError(ErrorKind::Argument, "",
                   flag + " needs " + image + " of at least " + std::to_string(kLegendMinWidth) +
                       "x" + std::to_string(kLegendMinHeight) +
                       " pixels to be readable, not --size " + size);
    try {
        return Font(findFontFile());
    } catch (const Error& e) {
        throwError(e.kind(), "", flag + ": " + e.what());
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

bool RenderFlags::cameraIsReset() const {
    return cameraFile.empty() && cameraPosition.empty() && cameraFocal.empty() && !parallelScale;
}

RenderOutputs RenderFlags::renderOutputs() const {
    RenderOutputs out;
    out.image = output;
    out.heatmap = heatmapFile;
    out.heatmapMax = heatmapMax;
    out.stats = statsFile;
    out.depth = depthFile;
    out.background = backgroundColor();
    out.legend = legendFont();
    out.roomForLegend = out.legend && cameraIsReset();
    return out;
}

std::vector<NamedFile> RenderFlags::outputs() const {
    std::vector<NamedFile> out;
    if (!output.empty()) out.push_back({"-o", output});
    if (!heatmapFile.empty()) out.push_back({"--heatmap", heatmapFile});
    if (!statsFile.empty()) out.push_back({"--stats", statsFile});
    if (!depthFile.empty()) out.push_back({"--depth", depthFile});
    return out;
}

std::vector<NamedFile> RenderFlags::inputs() const {
    const auto tfFile = splitColorMapFile(tf);  // FILE.json[:NAME]: the file
    std::vector<NamedFile> in{{"--tf", tfFile ? tfFile->first : tf}};
    if (!cameraFile.empty()) in.push_back({"--camera", cameraFile});
    if (!depthInFile.empty()) in.push_back({"--depth-in", depthInFile});
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
    checkExtension("--depth", depthFile, ".npy", "a NumPy array");
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
    // Data-parallel pieces' ghost cells reach the sample distance given (mpirun).
    if (vocabulary.given("sample_distance")) {
        const nlohmann::json v = vocabulary.value("sample_distance");
        if (v.is_number()) o.largestSampleDistance = v.get<float>();
    }
    return o;
}

std::uint64_t frameMemoryBytes(const RenderFlags& flags, std::uint64_t frames) {
    const auto [width, height] = parseSize("--size", flags.size);
    const std::uint64_t w = static_cast<std::uint64_t>(std::max(width, 0));
    const std::uint64_t h = static_cast<std::uint64_t>(std::max(height, 0));
    std::uint64_t bytes = w * h * kFrameBytesPerPixel;
    if (!flags.heatmapFile.empty()) bytes += (w + kHeatmapLegendWidth) * h * kHeatmapBytesPerPixel;
    return frames * bytes;
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

}  // namespace uvr::cli

// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "cli_common.h"
#include "setting_flags.h"

namespace uvr::cli {

/// What a single render writes beside its image and draws on it, taken from the flags once
/// (RenderFlags::renderOutputs) before any work.
struct RenderOutputs {
    std::string image;    ///< -o: the PNG ("-": standard output)
    std::string heatmap;  ///< --heatmap: the samples per pixel as a PNG ("" for none)
    /// --heatmap-max: the count at the top of the heat map's scale (none: the frame's largest).
    std::optional<std::uint32_t> heatmapMax;
    std::string stats;                ///< --stats: the frame report as JSON ("" for none)
    std::optional<Vec3f> background;  ///< --background: composited over it (none: RGBA)
    std::optional<Font> legend;       ///< --legend: the font it is drawn in (none: no legend)
    /// With --legend and a camera that is the reset one (turned, or parallel): it is moved back
    /// to keep the volume off the legend (clearColumns). Not a camera given by file or position.
    bool roomForLegend = false;
    std::string depth;  ///< --depth: the depth image as a .npy ("" for none)
};

/// Render options shared by `render` and `demo`, registered on a subcommand.
struct RenderFlags {
    std::string output;
    std::string field;
    std::string tf = "cool-to-warm";
    std::optional<std::string> opacity;  ///< unset: the JSON's Points, else ramp
    std::string range;
    bool logScale = false;  ///< --log
    std::string nanColor;   ///< --nan-color r,g,b[,a]; empty: the colour map's
    std::string size = "1024x1024";
    std::string cameraFile, cameraPosition, cameraFocal, cameraUp;
    std::optional<float> viewAngle;
    bool parallel = false;               ///< --parallel: parallel projection
    std::optional<float> parallelScale;  ///< unset: the camera file's, else the reset camera's
    float azimuth = 0.f, elevation = 0.f;
    /// The settings of the library's vocabulary (--method, --quality, --sample-distance, ...).
    SettingFlags vocabulary;
    std::vector<std::string> clipPlanes;         ///< --clip-plane ox,oy,oz,nx,ny,nz (repeatable)
    std::string clipBox;                         ///< --clip-box x0,y0,z0,x1,y1,z1
    std::vector<std::string> isoSurfaces;        ///< --iso VALUE[,OPACITY[,#RRGGBB]] (repeatable)
    std::optional<std::string> gradientOpacity;  ///< --gradient-opacity MAGNITUDE:SCALE,...
    std::uint32_t leafCells = 0;
    bool noSeedGrid = false;
    bool splitCells = false;
    std::string device = "auto";
    std::string buildDevice = "auto";
    std::string heatmapFile;
    std::optional<std::uint32_t> heatmapMax;  ///< needs --heatmap; 0: the frame's maximum
    std::string background;
    bool legend = false;  ///< draw a colour legend (title, bar, ticks) at the right edge
    std::string statsFile;
    std::string depthFile;  ///< --depth FILE.npy: depth out
    /// --depth-opacity: the opacity whose depth --depth writes (unset: kDefaultDepthOpacity).
    std::optional<float> depthOpacity;
    std::string depthInFile;  ///< --depth-in FILE.npy: depth in
    int threads = 0;

    /// Adds the flags to a subcommand; oneFrame adds those of a single render (output, heat map,
    /// stats, --no-skip, --no-adaptive), which `bench` chooses itself; withMethod adds --method.
    void registerOn(CLI::App& app, bool oneFrame = true, bool withMethod = true);
    /// Parses the flags into render settings; the default camera fits the bounds (of the mesh
    /// named source, which an error resetting the camera names). Choices made for the user (a
    /// view up picked because the default one is parallel to the view direction) are appended
    /// to notes when given, for the caller to print.
    RenderSettings settings(const Bounds3f& bounds, const std::string& source = "",
                            std::vector<std::string>* notes = nullptr) const;
    /// With --legend, the font it is drawn with (found through fontconfig), after checking that
    /// --size leaves room for it; throws Error naming --legend and what is missing. Without
    /// --legend, none.
    std::optional<Font> legendFont() const;
    /// The font of an annotation `flag` asks for (--legend, --time-label), after checking that
    /// --size gives `image` ("an image", "frames") large enough to read it; Error(Argument) or
    /// the font lookup's error, prefixed by the flag.
    Font annotationFont(const std::string& flag, const std::string& image) const;
    /// Checks every flag that does not need the mesh (and, for a .uvrm meshFile, that --field
    /// names one of the fields its header lists; with --legend, that a font is found), so that a
    /// bad flag fails before minutes of reading; throws Error(Argument) as settings() would.
    void checkBeforeLoading(const std::string& meshFile = "") const;
    /// The --background colour, if given (checked to lie in [0, 1]).
    std::optional<Vec3f> backgroundColor() const;
    /// The outputs of a single render (-o, --heatmap, --heatmap-max, --stats, --background,
    /// --legend with its font found), checked.
    /// The camera is the reset one, perhaps turned (--azimuth, --elevation), made parallel
    /// or given another view angle: no --camera file, position, focal point or parallel scale.
    bool cameraIsReset() const;
    RenderOutputs renderOutputs() const;
    /// The camera flags' own checks (--parallel-scale without a parallel camera, --view-angle
    /// with one or out of range, non-finite --azimuth/--elevation); fileParallel: the --camera
    /// file is parallel. Run before loading and again by settings().
    void checkCameraFlags(bool fileParallel) const;
    /// The settings the flags give that do not depend on the mesh (no camera).
    RenderSettings baseSettings() const;
    /// The files a single render writes (-o, --heatmap, --stats), for checks before any work.
    std::vector<NamedFile> outputs() const;
    /// The files the flags read (--tf when it names a file, --camera).
    std::vector<NamedFile> inputs() const;
    /// Checks before any work that every output can be written and that none names an input
    /// (the mesh file, when not empty, or a file the flags read) or another output.
    void checkFiles(const std::string& meshFile) const;
    /// The method the flags ask for: --method's, except that auto with settings that tune
    /// sampling (tunesAdaptive: --quality 0.995, --sample-distance, --sampling point, --no-skip,
    /// ...) or a partition flag (--leaf-cells, --no-seed-grid) is the adaptive method they tune.
    RenderMethod requestedMethod() const;
    /// Refuses (Error(Argument), one line) flags that --method's integrator would ignore: a
    /// setting it does not read (settingReadBy: --quality with --method reference, --sampling
    /// with exact) and --leaf-cells or --no-seed-grid without the adaptive method.
    void refuseIgnoredFlags() const;
    /// What the renderer prepares and where (--device, --build-device, --leaf-cells,
    /// --no-seed-grid): partitions only for the adaptive method, the mesh BVH only for the
    /// reference and exact methods, what auto picks for auto (PrepareOptions::forAuto), and the
    /// mesh BVH also when withReference.
    RendererOptions rendererOptions(bool withReference = false) const;
};

/// Host bytes of `frames` frames at the flags' --size written as PNGs (with a heat map each when
/// --heatmap is given), for checks before any work.
std::uint64_t frameMemoryBytes(const RenderFlags& flags, std::uint64_t frames = 1);

/// Checks before any work that the frame buffers of the flags' --size fit --max-memory.
void checkFrameMemory(const RenderFlags& flags, const Context& ctx);

}  // namespace uvr::cli

// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include <chrono>
#include <optional>
#include <string>

#include "setting_flags.h"
#include "uvr/uvr.h"

namespace uvr::cli {

/// What every subcommand shares: progress messages on stderr ("uvr: reading x.vtk", silenced by
/// --quiet) and the memory limit of loads (--max-memory).
class Context {
public:
    bool quiet = false;
    std::uint64_t maxMemoryBytes = 0;  ///< a whole load, image buffers, meshes; 0 = no limit
    /// How the default limit was found (MemoryDefault::how); empty when --max-memory was given.
    std::string maxMemoryDefault;
    /// Prints a step message (control characters and invalid UTF-8 escaped: one line).
    void step(const std::string& message) const;
    /// Prints "uvr: warning: MESSAGE", also when quiet: the command goes on and exits 0.
    void warn(const std::string& message) const;
    /// Prints a message with the seconds since `start`.
    void done(const std::string& message, std::chrono::steady_clock::time_point start) const;
    /// Records what uvr is doing now and with which file ("" for none), for the message when
    /// memory runs out: "FILE: out of memory while WHAT".
    void setActivity(const std::string& file, const std::string& what) const;
    /// The one-line message for running out of memory during the current activity.
    std::string outOfMemoryMessage() const;
    /// `message` in the CLI's spelling: each setting the library mentions ("`max_step`") as its
    /// flag ("--max-step", or "--no-seed-grid" where only that exists), looked up in `app`.
    std::string spell(const std::string& message) const;
    /// An error's message in the CLI's spelling (a SettingError: "--quality 1.5: ...").
    std::string spell(const Error& error) const;
    /// The command line, for spell (set once by main).
    const CLI::App* app = nullptr;

private:
    mutable std::string activityFile_, activity_;
};

/// Starts CUDA's initialisation in the background (startCudaWarmUp) unless --device is cpu, and
/// waits for it when destroyed.
class CudaWarmUp {
public:
    explicit CudaWarmUp(const std::string& device);
    ~CudaWarmUp();
    CudaWarmUp(const CudaWarmUp&) = delete;
    CudaWarmUp& operator=(const CudaWarmUp&) = delete;
};

/// Applies a --threads value: 0 keeps the default (OMP_NUM_THREADS when set, else every hardware
/// thread), 1 .. cpu::maxThreadCount() sets the count; anything else throws Error(Argument) naming
/// the flag and the limit. Every command with --threads uses this one rule.
void applyThreads(int threads);

/// Caps an OMP_NUM_THREADS above cpu::maxThreadCount() with a note on stderr (called once at
/// start-up).
void capEnvironmentThreads();

/// Help text of every --threads flag.
std::string threadsHelp();

/// The JSON text uvr writes (indented by 2): names from files are arbitrary bytes, so invalid
/// UTF-8 in strings becomes U+FFFD instead of failing (control characters are escaped by JSON).
std::string jsonText(const nlohmann::json& j);

/// Parses a byte count with an optional K, M, G or T suffix (powers of 1024) for a flag.
std::uint64_t parseBytes(const std::string& flag, const std::string& text);

/// The default --max-memory and how it was found.
struct MemoryDefault {
    std::uint64_t bytes = 0;  ///< 0: no limit (nothing credible was found)
    std::string how;          ///< e.g. "80% of 128 GiB (1024 memory blocks of 128 MiB in ...)"
};

/// The default --max-memory: 80% of the machine's physical memory as detectHostMemory finds it
/// (the larger of MemTotal and the hot-pluggable memory blocks, capped by a cgroup limit).
MemoryDefault defaultMaxMemory();

/// Parses "x,y,z" for a flag; throws Error(Argument) naming the flag.
Vec3f parseVec3(const std::string& flag, const std::string& text);
/// Parses "lo,hi" for a flag; throws Error(Argument) naming the flag.
std::pair<float, float> parseRange(const std::string& flag, const std::string& text);
/// Parses "WxH" for a flag; throws Error(Argument) naming the flag.
std::pair<int, int> parseSize(const std::string& flag, const std::string& text);

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
    /// The settings of the library's vocabulary (--method, --quality, --step, ...).
    SettingFlags vocabulary;
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
    /// Checks every flag that does not need the mesh (and, for a .uvrm meshFile, that --field
    /// names one of the fields its header lists; with --legend, that a font is found), so that a
    /// bad flag fails before minutes of reading; throws Error(Argument) as settings() would.
    void checkBeforeLoading(const std::string& meshFile = "") const;
    /// The --background colour, if given (checked to lie in [0, 1]).
    std::optional<Vec3f> backgroundColor() const;
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
    /// sampling (tunesAdaptive: --quality 0.995, --step, --sampling point, --no-skip, ...) or a
    /// partition flag (--leaf-cells, --no-seed-grid) is the adaptive method they tune.
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

/// Prepares `field` of a mesh into a Renderer as the flags ask, with progress messages, and
/// prints where it renders (the GPU, what was uploaded).
std::unique_ptr<Renderer> makeRenderer(const Mesh& mesh, const ScalarField& field,
                                       const RendererOptions& options, const Context& ctx);

/// Help text of every command's mesh FILE argument.
inline constexpr const char* kMeshFileHelp =
    "Mesh file (.vtk, .vtu, .pvtu, .vtkhdf, .e/.exo/.ex2 Exodus II, .pvd, .uvrm) or a quoted "
    "numbered series ('run_*.vtu')";

/// Which time step of a series a command reads: --time T (the last step at or before T, as
/// ParaView snaps) or --step-index I; neither: the first.
struct StepFlags {
    std::optional<double> time;
    std::optional<std::size_t> index;

    /// Adds --time and --step-index (exclusive) to a subcommand.
    void registerOn(CLI::App& app);
    /// The step of `series` the flags pick; Error(Argument) naming --step-index when out of range.
    std::size_t pick(const MeshSeries& series) const;
};

/// Opens a mesh file or series (a .pvd, a quoted 'run_*.vtu' pattern, a file with time steps)
/// with --max-memory applied to each step's read; progress, when given, hears each read.
std::unique_ptr<MeshSeries> openSeries(const std::string& path, const Context& ctx,
                                       std::function<void(double)> progress = {});

/// Loads a mesh (the step `steps` picks of a series) with progress messages; prints the reader's
/// notes, and which step of how many it read when the file has several.
Mesh loadMesh(const std::string& path, const Context& ctx, const StepFlags& steps = {});

/// Checks a mesh for rendering `field` (validateMesh, its findings printed) and summarises what
/// rendering needs of it; throws Error(Validation) when no cell renders. checkSeconds, when
/// given, receives the time of the check.
SourceSummary checkForRendering(const Mesh& mesh, const ScalarField& field,
                                const std::string& source, const Context& ctx,
                                double* checkSeconds = nullptr);

/// The time step the flags ask for, as a prepared cache's key records it ("" for the first).
std::string stepKey(const StepFlags& steps);

/// A prepared mesh's source, as a render reports it: the mesh file, its summary, and the
/// prepared cache it came from (empty when prepared from the mesh).
struct RenderSource {
    std::string path;
    SourceSummary summary;
    double checkSeconds = 0.0;  ///< the mesh's check (0 from a cache)
    std::string cacheFile;
    double cacheReadSeconds = 0.0;
};

/// Prepares, renders and writes the PNG (and stats JSON); returns the result (with --legend, its
/// image carries the legend). The mesh is taken over and freed once its cells are split.
RenderResult renderAndWrite(Mesh&& mesh, const std::string& source, const RenderFlags& flags,
                            const Context& ctx);

/// `render`'s --cache FILE and --no-cache.
struct CacheFlags {
    std::string file;  ///< --cache; empty: MESH.uvrprep when it exists
    bool off = false;  ///< --no-cache
    /// Adds the flags (exclusive) to a subcommand.
    void registerOn(CLI::App& app);
};

/// Renders from a prepared cache instead of the mesh when one applies and writes the outputs as
/// renderAndWrite does: --cache FILE (a mismatch or a damaged file is an error), else
/// MESH.uvrprep when it exists (a stale or damaged one is set aside with a warning saying why:
/// false is returned and the caller prepares from the mesh). False without a cache.
bool renderFromCache(const std::string& meshFile, const RenderFlags& flags, const StepFlags& steps,
                     const CacheFlags& cache, const Context& ctx);

/// A Renderer over a mesh already prepared (read from a prepared cache) on `device`; prints
/// where it renders as the other makeRenderer does.
std::unique_ptr<Renderer> makeRenderer(PreparedMesh prepared, Device device, const Context& ctx);

/// Refuses with Error(Resource) an estimate above --max-memory: "WHAT would need about N bytes,
/// more than the --max-memory limit of M bytes" (what names the flags responsible).
void checkMemoryEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes);

/// checkMemoryEstimate for image buffers; without an explicit --max-memory they must also fit
/// kDefaultFrameMemoryBytes (Error(Resource) naming the need, the limit and the flag).
void checkFrameEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes);

/// Host bytes of `frames` frames at the flags' --size written as PNGs (with a heat map each when
/// --heatmap is given), for checks before any work.
std::uint64_t frameMemoryBytes(const RenderFlags& flags, std::uint64_t frames = 1);

/// Checks before any work that the frame buffers of the flags' --size fit --max-memory.
void checkFrameMemory(const RenderFlags& flags, const Context& ctx);

/// Registers the subcommands.
void addInfoCommand(CLI::App& app, Context& ctx);
void addRenderCommand(CLI::App& app, Context& ctx);
void addDemoCommand(CLI::App& app, Context& ctx);
void addConvertCommand(CLI::App& app, Context& ctx);
void addGenerateCommand(CLI::App& app, Context& ctx);
void addRefineCommand(CLI::App& app, Context& ctx);
void addCompareCommand(CLI::App& app, Context& ctx);
void addBenchCommand(CLI::App& app, Context& ctx);
void addPresetsCommand(CLI::App& app, Context& ctx);
void addViewCommand(CLI::App& app, Context& ctx);
void addAnimateCommand(CLI::App& app, Context& ctx);
void addPrepareCommand(CLI::App& app, Context& ctx);

}  // namespace uvr::cli

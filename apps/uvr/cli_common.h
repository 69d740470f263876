// SPDX-License-Identifier: MIT
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include <chrono>
#include <optional>
#include <string>

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
    /// `message` in the CLI's spelling: each setting the library mentions ("`max_sample_distance`")
    /// as its flag ("--max-sample-distance", or "--no-seed-grid" where only that exists), looked up
    /// in `app`.
    std::string spell(const std::string& message) const;
    /// An error's message in the CLI's spelling (a SettingError: "--quality 1.5: ...").
    std::string spell(const Error& error) const;
    /// The command line, for spell (set once by main).
    const CLI::App* app = nullptr;
    /// The ranks of a data-parallel run (`mpirun -n N uvr render`; set by main), else null.
    Communicator* comm = nullptr;
    /// True where messages and outputs are written: rank 0 of a data-parallel run, any other
    /// run.
    bool root() const { return !comm || comm->rank() == 0; }
    /// True in a data-parallel run of more than one rank.
    bool dataParallel() const { return comm && comm->size() > 1; }
    /// Runs `write` where outputs are written (root()); in a data-parallel run every rank then
    /// agrees on its failure (collective), so all stop with the root's error.
    template <class F>
    void rootWrites(F&& write) const {
        if (!comm) return write();
        agreeOn(*comm, [&] {
            if (root()) write();
        });
    }

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

/// Throws Error(Argument): "FLAG 'TEXT': expected WHAT".
[[noreturn]] void badFlag(const std::string& flag, const std::string& text,
                          const std::string& what);
/// Parses `count` comma-separated finite numbers for a flag; badFlag(flag, text, what) otherwise.
std::vector<float> parseFloats(const std::string& flag, const std::string& text, std::size_t count,
                               const std::string& what);
/// Parses "x,y,z" for a flag; throws Error(Argument) naming the flag.
Vec3f parseVec3(const std::string& flag, const std::string& text);
/// Parses "lo,hi" for a flag; throws Error(Argument) naming the flag.
std::pair<float, float> parseRange(const std::string& flag, const std::string& text);
/// Parses "WxH" for a flag; throws Error(Argument) naming the flag.
std::pair<int, int> parseSize(const std::string& flag, const std::string& text);

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

/// Refuses with Error(Resource) an estimate above --max-memory: "WHAT would need about N bytes,
/// more than the --max-memory limit of M bytes" (what names the flags responsible).
void checkMemoryEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes);

/// checkMemoryEstimate for image buffers; without an explicit --max-memory they must also fit
/// kDefaultFrameMemoryBytes (Error(Resource) naming the need, the limit and the flag).
void checkFrameEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes);

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

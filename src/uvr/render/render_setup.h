// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "uvr/accel/bvh.h"
#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/lbvh.h"
#include "uvr/accel/macro_grid.h"
#include "uvr/accel/seed_grid.h"
#include "uvr/core/progress.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_kernel.h"
#include "uvr/render/image.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/render/render_method.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

/// What prepareMesh builds besides the cells, BVH and neighbours.
struct PrepareOptions {
    bool meshBvh = true;     ///< build the BVH over all cells the reference marcher needs
    bool partitions = true;  ///< build the k-d partitions the partition integrator needs
    /// Also what RenderMethod::Auto renders with (autoMethod for the device autoOnGpu names,
    /// decided once the cells are split): the mesh BVH or the partitions. A front end whose
    /// frames are all Auto sets this and neither meshBvh nor partitions.
    bool forAuto = false;
    /// The device PreparedMesh::autoChoice is made for: the GPU (else the CPU).
    bool autoOnGpu = false;
    bool seedGrids = true;   ///< with partitions: the seed grids that long steps locate from
    bool macroGrids = true;  ///< with partitions: the macrocells the error-bound rule steps by
    /// With partitions: cells per leaf of the cell tree (buildCellTree); the CPU's small leaves
    /// by default, kCellTreeLeaf where the renderer is a GPU (RendererOptions::prepareOptions).
    /// Meshes of up to 2^24 cells get leaves of at most kCpuCellTreeLeaf whatever this asks
    /// (searches are not rare on small non-convex meshes: prepareMesh).
    std::uint32_t cellTreeLeaf = kCpuCellTreeLeaf;
    TetrahedralizeOptions cells;  ///< native cells or the split into tetrahedra
    KdBuildOptions kd;
    /// When set, the mesh BVH is an LBVH from this builder (buildLbvhCuda: on the GPU, in
    /// seconds for 100M+ tetrahedra); else a binned SAH tree built on the CPU threads.
    LbvhBuilder lbvh;
    /// When set, the k-d tree comes from this splitter (buildKdTreeCuda: on the GPU); it
    /// overrides kd.splitter.
    KdSplitter kdSplitter;
    /// When set, the face neighbours come from this builder (buildTetNeighborsCuda: on the GPU),
    /// the same table as buildTetNeighbors. It is given the points' welded ids
    /// (coincidentPointIds of the tetrahedra's points), found on a thread of their own beside
    /// the split.
    std::function<std::vector<std::uint32_t>(const TetMesh&, const std::vector<std::uint32_t>&,
                                             const FractionFn&)>
        faceMatcher;
    /// When set, the seed grids come from this builder (buildSeedGridsCuda: on the GPU).
    SeedBuilder seedBuilder;
    /// When set (and with macroGrids), the macrocells and the partitions' gradient spreads come
    /// from this builder (buildMacroGridsCuda: on the GPU).
    MacroBuilder macroBuilder;
    /// Called once the cells are split (tetrahedralize), after which prepareMesh reads nothing of
    /// the source mesh: a caller holding the only copy may free it then, so a one-shot render of
    /// a billion cells does not hold the mesh as read beside the prepared one.
    std::function<void()> afterSplit;
    std::string builderDevice = "cpu";  ///< where the builders above build (progress messages)
    std::uint64_t builderMinTets = 0;   ///< use them only from this many cells
};

/// A mesh made ready for rendering one field: cells (tetrahedra, native cells), BVH, face
/// neighbours and (optionally)
/// k-d partitions, built once and reused by every frame and transfer-function change.
struct PreparedMesh {
    TetMesh tets;
    Bvh bvh;  ///< over all cells; empty unless PrepareOptions::meshBvh
    /// Face neighbours as buildTetNeighbors gives them (host-side builds: macrocells).
    std::vector<std::uint32_t> neighbors;
    /// The same neighbours in the kernels' layout (compactNeighbors).
    CompactNeighbors neighborCodes;
    /// With partitions: the tree of runs of consecutive cells (buildCellTree) that the partition
    /// method searches where walks and seeds do not locate a sample.
    Bvh cellTree;
    std::optional<KdPartitions> kd;
    std::optional<SeedGrids> seeds;  ///< per-partition walk starts (with partitions)
    /// Per-partition macrocells (with partitions): value ranges and gradient spreads finer than
    /// a partition's, for skipping and the error-bound rule's steps.
    std::optional<MacroGrids> macro;
    /// Per partition (with partitions): the spread of its cells' field gradients, the diagonal
    /// of their bounding box (partitionGradientSpread), for the error-bound step rule.
    std::vector<float> gradientSpread;
    /// Per partition (with partitions): 1 where a cell has a NaN value (partitionNanFlags);
    /// empty when the field has none.
    std::vector<std::uint8_t> partitionNan;
    std::uint64_t sourceCells = 0;  ///< cells of the mesh before splitting
    /// What RenderMethod::Auto renders it with on PrepareOptions::autoOnGpu's device (made once
    /// the cells are split; resolveMethod makes it again for the other device).
    std::optional<AutoMethodChoice> autoChoice;
    double splitSeconds = 0.0;      ///< time to split cells (or keep them native)
    double bvhSeconds = 0.0;        ///< time to build the BVH
    double adjacencySeconds = 0.0;  ///< time to find face neighbours
    bool builtElsewhere = false;    ///< PrepareOptions' builders (the GPU's) built parts of it
    /// Wall seconds of every phase prepareMesh ran, in order: "split" (with the Morton order and
    /// the kernels' blocks), "bvh", "neighbours" (with their codes), "partitions" (with their
    /// value ranges), "cell_tree", "seed_grids", "gradient_spreads", "nan_flags", "macrocells"
    /// (with the gradient spreads, which then have no phase of their own, when
    /// PrepareOptions::macroBuilder builds them). With PrepareOptions::faceMatcher the cell tree
    /// is built beside the neighbours and the neighbours' codes ("neighbour_codes", last) beside
    /// the later phases, on threads of their own: their seconds overlap the others'.
    std::vector<std::pair<std::string, double>> phaseSeconds;
    /// The prepared cache it was read from (readPreparedCache), holding only what rendering
    /// reads; empty when prepared from a mesh. updateFieldValues refuses such a mesh.
    std::string cacheFile;
    std::uint64_t valueUpdates = 0;   ///< times updateFieldValues gave it new values
    double valueUpdateSeconds = 0.0;  ///< time the last updateFieldValues took

    /// The mesh as kernels read it: tetrahedra from their blocks only (tets null), points and
    /// values only where native cells or cell data need them (what the GPU holds, too).
    TetMeshView kernelMesh() const {
        TetMeshView v = tets.view();
        v.tets = nullptr;
        if (!v.hasNative()) {
            v.points = nullptr;
            if (!v.cellCentered) v.values = nullptr;
        }
        return v;
    }
    /// Point locator over this mesh, as kernels use it.
    TetLocator locator() const { return {kernelMesh(), bvh.view(), neighborCodes.view()}; }
};

/// Optional progress report of a preparation: `step` names each phase as it starts ("finding
/// face neighbours", ...) and `fraction` tells how far the phase named last has come, in [0, 1],
/// increasing within the phase (only phases that can take long report it, ending with 1; from
/// one thread at a time, any thread; it must not throw). Either may be empty. Any callable taking
/// a step name converts to one with only `step`.
struct ProgressFn {
    std::function<void(const std::string&)> step;  ///< a phase starts: its name
    FractionFn fraction;                           ///< how far the phase named last has come

    /// No reports.
    ProgressFn() = default;
    /// Both callbacks.
    ProgressFn(std::function<void(const std::string&)> onStep, FractionFn onFraction)
        : step(std::move(onStep)), fraction(std::move(onFraction)) {}
    /// Only step names, from any callable taking one (a lambda, a std::function).
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, ProgressFn> &&
                                                std::is_invocable_v<F&, const std::string&>>>
    ProgressFn(F&& onStep)  // NOLINT(google-explicit-constructor): lambdas convert
        : step(std::forward<F>(onStep)) {}

    /// Names a phase that starts (nothing when step is empty).
    void operator()(const std::string& name) const {
        if (step) step(name);
    }
    /// Whether anything is reported.
    explicit operator bool() const { return step || fraction; }
};

/// Splits cells (or keeps them native), builds the BVH over them and the face-neighbour table,
/// and what options ask for besides. `progress` hears each phase of PreparedMesh::phaseSeconds
/// named as it starts, in that order, and the fraction done of the long ones (split,
/// neighbours, partitions, cell tree, gradient spreads).
PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field,
                         const PrepareOptions& options, const ProgressFn& progress = {});
/// prepareMesh with the default options.
PreparedMesh prepareMesh(const MeshView& mesh, const ScalarField& field);

/// Gives a prepared mesh new values of a field of the same source mesh (a time step, or another
/// field), rebuilding nothing geometric: tetrahedra, BVHs, neighbours, k-d tree, partition cell
/// lists, seed grids and macrocell layouts stay as they are (not reallocated); the values, the
/// value range, the partitions' value ranges, gradient spreads and NaN flags and the macrocells
/// are recomputed by the same functions prepareMesh uses (assignTetValues,
/// computePartitionValueRanges, partitionGradientSpread, partitionNanFlags, fillMacroCells), so
/// frames equal those of a fresh prepareMesh of the new values bit for bit. Throws
/// Error(Argument) when the field does not hold one value per point (or cell) of the source
/// mesh, or when the mesh was read from a prepared cache (PreparedMesh::cacheFile: the arrays
/// new values need are not there); the prepared mesh is unchanged then.
void updateFieldValues(PreparedMesh& mesh, const ScalarField& field);

/// Per partition, the diagonal of the bounding box of the field gradients of its cells (each
/// linear tetrahedron's constant gradient, a native cell's at its corners and centre:
/// cellGradientBounds): it bounds how much the derivative of the field along
/// any ray varies inside the partition. 0 for a partition without cells or with a linear field;
/// infinite for a cell-centred field (piecewise constant: its jumps have no gradient bound).
/// Cells with non-finite gradients (degenerate, or NaN values) are left out. `progress` hears the
/// fraction done.
std::vector<float> partitionGradientSpread(const TetMesh& tets, const KdPartitions& kd,
                                           const FractionFn& progress = {});

/// Per partition, 1 where one of its cells has a NaN value (a vertex's, or the cell's own for
/// cell data); empty when no cell has one. Partition value ranges leave NaN out, so skipping
/// needs these to keep NaN regions of non-zero NaN opacity (shadeNan).
std::vector<std::uint8_t> partitionNanFlags(const TetMesh& tets, const KdPartitions& kd);

/// Default sample spacing s1: half the edge of a cube with the mean tetrahedron volume of the
/// split, 0.5 * cbrt(totalVolume / splitTetCount): about two to three samples per tetrahedron along
/// a ray; at most the bounds' diagonal / kMinSamplesPerDiagonal (a mesh of few cells is cheap to
/// sample finely, and where a ray enters and leaves the mesh a sample's share is uncertain by a
/// step); at least kMinDefaultStepFraction of the diagonal (a mesh of slivers has a tiny mean
/// volume).
float defaultStep(const TetMesh& mesh);

/// Fewest samples the default step takes across the bounds' diagonal (it decides the step of
/// meshes below about 400,000 tetrahedra).
inline constexpr double kMinSamplesPerDiagonal = 256;

/// Smallest default step relative to the bounds' diagonal: at most 10^4 samples across the mesh
/// (a uniform mesh reaches this at about 2 * 10^10 tetrahedra).
inline constexpr double kMinDefaultStepFraction = 1e-4;

/// ParaView's default ScalarOpacityUnitDistance: bounds diagonal / cbrt(cell count).
float defaultOpacityUnit(const Bounds3f& bounds, std::uint64_t cellCount);

/// Default --quality: the error-bound rule's SSIM target against the exact integrator.
inline constexpr float kDefaultQuality = 0.99f;
/// Range of --quality.
inline constexpr float kMinQuality = 0.5f;
inline constexpr float kMaxQuality = 0.9999f;

/// Tolerance per unit of (1 - quality) (toleranceForQuality).
inline constexpr float kToleranceScale = 5.f;

/// The error-bound rule's tolerance (StepRuleParams::tolerance, optical depth error per opacity
/// unit) for a quality: measured on the evaluation matrix (docs/PERFORMANCE.md), the worst-case
/// SSIM against exact stays at or above the quality for tolerance kToleranceScale * (1 -
/// quality).
float toleranceForQuality(float quality);

/// What to render and how.
struct RenderSettings {
    RenderMethod method = RenderMethod::Auto;
    StepRule stepRule = StepRule::ErrorBound;  ///< how the partition method picks steps
    /// The error-bound rule's target: the SSIM against the exact integrator that it aims at for
    /// typical data (toleranceForQuality), in [kMinQuality, kMaxQuality].
    float quality = kDefaultQuality;
    /// Sample-based methods integrate between consecutive samples (false: point samples with
    /// opacity correction, as in Morrical et al. 2019).
    bool preintegrated = true;
    float maxStep = 0.f;   ///< s2 of the adaptive step; 0 = kDefaultMaxStepFactor * s1
    float power = 2.f;     ///< variance rule: adaptive power p >= 1
    bool skip = true;      ///< skip partitions of zero maximum opacity
    bool adaptive = true;  ///< adaptive steps (false: every partition at s1)
    int width = 1024;
    int height = 1024;
    std::optional<Camera> camera;  ///< default: resetCamera on the mesh bounds
    TransferFunction tf;
    std::optional<std::pair<float, float>> range;  ///< default: the field's finite range
    float step = 0.f;                              ///< s1; 0 = defaultStep
    float opacityUnit = 0.f;                       ///< 0 = defaultOpacityUnit
    /// How the transfer function's opacities become extinction (default: ParaView's reading for
    /// unstructured data).
    OpacityLaw opacityLaw = kDefaultOpacityLaw;
    float terminationAlpha = 0.99f;
    /// Entries of the baked transfer function (a log-scale one gets more: logTableSize).
    int tfTableSize = 1024;
    /// Anti-aliasing: N x N rays per pixel (N in [1, kMaxSupersample]), their premultiplied
    /// colours averaged; a pixel's sample count is the sum over its rays. 1: one ray through
    /// the pixel's centre.
    int supersample = 1;
    /// With supersample > 1: each ray at a fixed hashed position inside its cell of the N x N
    /// grid instead of its centre (deterministic: the same rays every frame, on every device).
    bool jitter = false;
    /// Called during a CPU render with the fraction of the frame done, increasing, the last call
    /// with 1; from one thread at a time, and it must not throw. Empty: no reports. (A CUDA frame
    /// is one launch and reports nothing.)
    std::function<void(double)> progress;
};

/// The names every front end and report gives the step rules ("error", "variance") and the
/// sampling (RenderSettings::preintegrated: "preintegrated", else "point").
const char* stepRuleName(StepRule rule);
const char* samplingName(bool preintegrated);

/// Largest RenderSettings::supersample: 8 x 8 = 64 rays per pixel.
inline constexpr int kMaxSupersample = 8;

/// Throws Error(Argument) for settings that cannot render: image size outside [1, 16384] per
/// side, non-finite or non-positive step or opacity unit, bad range, bad camera, supersample
/// outside [1, kMaxSupersample].
void validateSettings(const RenderSettings& settings);

/// True when settings tune what only the sampling methods read, away from RenderSettings'
/// defaults (the step rule, quality, power, point sampling, s1 or s2, skipping or adaptive steps
/// off): RenderMethod::Auto then renders the adaptive method they tune.
bool tunesAdaptive(const RenderSettings& settings);

/// The method a frame renders with, and why when settings.method is Auto.
struct ResolvedMethod {
    RenderMethod method = RenderMethod::Partitions;
    std::string reason;  ///< with RenderMethod::Auto: one line (AutoMethodChoice::reason), else ""
};
/// settings.method, or for RenderMethod::Auto: the adaptive method when tunesAdaptive, else
/// mesh.autoChoice (made for the GPU when gpu, else the CPU; made now when it was made for the
/// other or not at all), the other of exact and adaptive where only its structures are prepared.
ResolvedMethod resolveMethod(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu);

/// Most samples one ray may take across the mesh bounds' diagonal at the step s1: the default
/// step takes 2 to 3 samples per cell, so this is a step 40 times finer than the default on a
/// mesh of a billion cells; finer steps are far smaller than any cell and change nothing seen.
inline constexpr double kMaxSamplesPerRay = 1e5;
/// Most samples a frame may take (pixels x samples per ray): about an hour for 16 CPU cores
/// (2e7 samples per second each), minutes on a GPU.
inline constexpr double kMaxFrameSamples = 1e12;

/// Upper bound on the work of a frame: every ray crossing the bounds' whole diagonal.
struct FrameWork {
    double samplesPerRay = 0.0;  ///< bounds diagonal / step
    double samples = 0.0;        ///< pixels x rays per pixel x samplesPerRay
};

/// The work estimate of a width x height frame of the bounds at a step, with raysPerPixel rays
/// per pixel (supersample squared).
FrameWork estimateFrameWork(const Bounds3f& bounds, float step, int width, int height,
                            int raysPerPixel = 1);

/// Host bytes per pixel of a frame rendered and written as a PNG: the float image (16), the
/// per-pixel sample counts (4) and the PNG's 8-bit rows (4).
inline constexpr std::uint64_t kFrameBytesPerPixel = 24;
/// Host bytes per pixel of a sample-count heat map written as a PNG (float image and 8-bit rows),
/// counted over the image and its legend.
inline constexpr std::uint64_t kHeatmapBytesPerPixel = 20;
/// Image-buffer bytes one frame (or a command's frames held together) may take unless a memory
/// limit is given explicitly: 2 GiB, an 8192 x 8192 frame (1.5 GiB) with room. A frame's memory
/// and time grow with its pixels whatever the mesh (16384 x 16384 of five tetrahedra: 6 GiB and
/// a minute), so larger frames must be asked for with an explicit limit.
inline constexpr std::uint64_t kDefaultFrameMemoryBytes = 2ull << 30;
/// Host bytes prepareMesh needs per tetrahedron, an upper estimate for memory limits: the
/// tetrahedra, the BVH with its build arrays, the neighbours, partitions and seed grids took
/// 120 to 130 bytes on 4-million-tetrahedron procedural meshes.
inline constexpr std::uint64_t kPrepareBytesPerTet = 160;

/// Default s2 / s1 of the adaptive step.
inline constexpr float kDefaultMaxStepFactor = 16.f;

/// Per-partition shading for a transfer function (Morrical et al. 2019, Sec. 2.1): each
/// partition's maximum opacity, rate and colour variance over its value range (O(1) per
/// partition from the table's range statistics, independent of cell count) and its step by the
/// rule (shadePartition; for the variance rule the variances are normalised to [0, 1] by the
/// minimum and maximum over the visible partitions).
std::vector<PartitionShading> computePartitionShading(const KdPartitions& kd,
                                                      const std::vector<float>& gradientSpread,
                                                      const TfRangeView& range,
                                                      const StepRuleParams& rule);

/// Per-macrocell shading for a transfer function and the error-bound rule: each macrocell's
/// maximum opacity over its value range and its step (shadePartition); an empty macrocell is
/// transparent.
std::vector<PartitionShading> computeMacroShading(const MacroGrids& macro, const TfRangeView& range,
                                                  const StepRuleParams& rule);

/// Whether the partition method steps by macrocells for these settings: the error-bound rule
/// with adaptive steps on a mesh with macrocell grids (the paper's variance rule and "skipping
/// only" keep one step per partition).
bool usesMacroCells(const PreparedMesh& mesh, const StepRuleParams& rule);

/// Host-side frame state built from settings: the baked table, the camera and the parameters.
struct FrameSetup {
    std::vector<Vec4f> tfTable;
    Vec4f tfNan;                         ///< colour and opacity of NaN values (TfTableView::nan)
    std::vector<std::int32_t> tfBreaks;  ///< tfTableBreaks of tfTable
    OpacityLaw opacityLaw = kDefaultOpacityLaw;  ///< RenderSettings::opacityLaw
    StepRuleParams stepRule;                ///< the partition method's step rule and its inputs
    std::vector<PartitionShading> shading;  ///< per partition (partition method only)
    /// Per macrocell (partition method with usesMacroCells; empty otherwise).
    std::vector<PartitionShading> macroShading;
    double tfUpdateSeconds = 0.0;  ///< range tables + shading of all partitions and macrocells
    float maxStep = 0.f;           ///< s2 in effect
    /// The prepared mesh's frame: camera, rays, params and maxStep are in its rendering units
    /// (lengths divided by frame.scale are in the file's units).
    MeshFrame frame;
    Camera camera;
    CameraRays rays;
    MarchParams params;
    /// The value range the table spans: the settings' or the field's; with a log-scale transfer
    /// function one from 0 or below starts at min(hi / 10^4, 1) (ParaView's AdjustRangeForLog).
    float rangeLo = 0.f, rangeHi = 1.f;
    /// What the setup changed or could not do as asked, one sentence each, for the user (the
    /// CLI prints them as warnings): a log range moved off 0, a log table too coarse at its low
    /// end.
    std::vector<std::string> notes;
    /// The method the frame renders with (resolveMethod: RenderMethod::Auto resolved) and, for
    /// Auto, why.
    ResolvedMethod method;

    /// The baked table as a view (host pointers); the setup must outlive it.
    TfTableView tfView() const;
    /// Scene view over a prepared mesh; both must outlive it.
    SceneView scene(const PreparedMesh& mesh) const;
    /// Partition scene view (the mesh must have partitions); both must outlive it.
    PartitionSceneView partitionScene(const PreparedMesh& mesh, bool skip) const;
};

/// The frame's output buffers and rays for the shared pixel kernel (both backends): pixels and
/// counts hold width * height entries on the device that renders.
inline FrameView makeFrameView(const RenderSettings& settings, const FrameSetup& setup,
                               Vec4f* pixels, std::uint32_t* sampleCounts) {
    return FrameView{pixels,
                     sampleCounts,
                     settings.width,
                     settings.height,
                     setup.rays,
                     settings.supersample,
                     settings.jitter && settings.supersample > 1};
}

/// Resolves defaults (the method for the GPU when gpu, else the CPU: resolveMethod) and
/// validates; throws Error(Argument) on bad settings. For the partition method on the CPU it also
/// computes the per-partition shading (the CUDA backend computes it on the GPU).
FrameSetup makeFrameSetup(const PreparedMesh& mesh, const RenderSettings& settings,
                          bool gpu = false);

/// Statistics of one rendered frame.
struct RenderStats {
    double seconds = 0.0;                 ///< wall time of the frame (rendering only)
    std::uint64_t samples = 0;            ///< samples taken
    std::uint64_t walkSteps = 0;          ///< cells tested while walking
    std::uint64_t bvhQueries = 0;         ///< point locations that fell back to the BVH
    std::uint64_t partitionsVisited = 0;  ///< partitions entered by rays (partition method)
    std::uint64_t partitionsSkipped = 0;  ///< of those, skipped as fully transparent
    int width = 0, height = 0;
    int supersample = 1;  ///< N x N rays per pixel

    /// Adds another frame part's counters.
    void merge(const RenderStats& o) {
        samples += o.samples;
        walkSteps += o.walkSteps;
        bvhQueries += o.bvhQueries;
        partitionsVisited += o.partitionsVisited;
        partitionsSkipped += o.partitionsSkipped;
    }
    /// Adds one ray's counters.
    void add(const RayCounters& c) {
        samples += c.samples;
        walkSteps += c.locate.walkSteps;
        bvhQueries += c.locate.bvhQueries;
        partitionsVisited += c.partitionsVisited;
        partitionsSkipped += c.partitionsSkipped;
    }
    /// Samples per pixel (summed over its rays), averaged over the image.
    double meanSamplesPerPixel() const {
        return width > 0 && height > 0 ? static_cast<double>(samples) / (double(width) * height)
                                       : 0.0;
    }
    /// Rays traced: pixels x supersample^2.
    std::uint64_t rays() const {
        return static_cast<std::uint64_t>(width > 0 ? width : 0) *
               static_cast<std::uint64_t>(height > 0 ? height : 0) *
               static_cast<std::uint64_t>(supersample) * static_cast<std::uint64_t>(supersample);
    }
    /// Samples per ray, averaged over the rays.
    double meanSamplesPerRay() const {
        return rays() > 0 ? static_cast<double>(samples) / static_cast<double>(rays()) : 0.0;
    }
};

/// A rendered frame: image, per-pixel sample counts, statistics.
struct RenderResult {
    Image image;
    std::vector<std::uint32_t> sampleCounts;  ///< per pixel, row-major
    RenderStats stats;
    FrameSetup setup;
};

}  // namespace uvr

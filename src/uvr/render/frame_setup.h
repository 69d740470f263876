// SPDX-License-Identifier: MIT
#pragma once

// The frame setup: settings resolved against a prepared mesh (the method, the baked transfer
// function, the camera in the mesh's units, the partitions' shading), and what a frame returns.

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/macro_grid.h"
#include "uvr/prepare/prepared_mesh.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_kernel.h"
#include "uvr/render/image.h"
#include "uvr/render/render_settings.h"
#include "uvr/render/scene_view.h"

namespace uvr {

/// The method a frame renders with, and why when settings.method is Auto.
struct ResolvedMethod {
    RenderMethod method = RenderMethod::Partitions;
    std::string reason;  ///< with RenderMethod::Auto: one line (AutoMethodChoice::reason), else ""
    /// Auto on adaptive, both the partitions and the mesh BVH prepared, one process: the
    /// AutoMethodChoice's adaptiveSampleCost, at which weighReference weighs the reference once
    /// the partitions are shaded; else 0.
    double weighReference = 0.0;
};
/// settings.method, or for RenderMethod::Auto: the adaptive method when tunesAdaptive, else
/// mesh.autoChoice (made for the GPU when gpu, else the CPU; made now when it was made for the
/// other or not at all), the other of exact and adaptive where only its structures are prepared.
ResolvedMethod resolveMethod(const PreparedMesh& mesh, const RenderSettings& settings, bool gpu);

/// Samples per unit of ray length, summed over the partitions weighted by their boxes' volume (a
/// random line's length inside a convex region is proportional to its volume, so this is
/// proportional to the samples of rays in every direction): the adaptive method's under a
/// frame's partition shading, and the reference's at s1.
struct SampleEstimate {
    double adaptive = 0.0;   ///< 1 / step in a visible partition, none in a skipped one
    double reference = 0.0;  ///< 1 / s1 in every partition
    /// Box volume of the visible partitions whose own step is below s1 (errorBoundStep): where
    /// the error bound finds s1 too long, so the reference is less right than the adaptive
    /// method. A partition marching by its macrocells counts too: its macrocells' ranges and
    /// spreads lie within its own, so one of them below s1 puts it below s1.
    double finer = 0.0;
};
/// The estimate for `shading` (one per partition of kd); a partition marching by its macrocells
/// counts macroDensity[p] (macroSampleDensity; may be empty when none does).
SampleEstimate estimateSamples(const KdPartitions& kd, const std::vector<PartitionShading>& shading,
                               const std::vector<float>& macroDensity, float s1);

/// Most samples one ray may take across the mesh bounds' diagonal at the step s1: the default
/// step takes 2 to 3 samples per cell, so this is a step 40 times finer than the default on a
/// mesh of a billion cells; finer steps are far smaller than any cell and change nothing seen.
inline constexpr double kMaxSamplesPerRay = 1e5;
/// A sample distance that leaves fewer samples than this along the bounds' diagonal gets a note
/// (the default leaves at least kMinSamplesPerDiagonal): the image is coarse (and users who
/// wrote `--step 3` when this was --step meant time step 3).
inline constexpr double kFewSamplesAcross = 16;
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
    /// Depth in and out: the unit view direction and the depth along it at which the rays
    /// start (a parallel projection's rays start in front of the camera), in rendering units.
    Vec3f viewDirection{0.f, 0.f, -1.f};
    float rayStartDepth = 0.f;
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

/// With f.method.weighReference > 0 and f.shading made (the partitions shaded): the reference
/// where the adaptive method's estimated samples (estimateSamples) are not weighReference times
/// fewer than the reference's, its reason saying so; the adaptive method otherwise, its reason
/// saying by how much (on the GPU when gpu, else the CPU), and always where the adaptive method
/// steps below s1 somewhere (SampleEstimate::finer: the reference would not be as right).
/// Either way weighReference is 0 after.
void weighReference(FrameSetup& f, const PreparedMesh& mesh, const std::vector<float>& macroDensity,
                    bool gpu);

/// The frame's output buffers and rays for the shared pixel kernel (both backends): pixels and
/// counts hold width * height entries on the device that renders, as do depth (depth out, or
/// null), depthIn (depth in, or null) and stopAlpha (stop in, or null).
inline FrameView makeFrameView(const RenderSettings& settings, const FrameSetup& setup,
                               Vec4f* pixels, std::uint32_t* sampleCounts, float* depth = nullptr,
                               const float* depthIn = nullptr, const float* stopAlpha = nullptr,
                               const float* depthAlphas = nullptr) {
    FrameView v;
    v.pixels = pixels;
    v.sampleCounts = sampleCounts;
    v.width = settings.width;
    v.height = settings.height;
    v.rays = setup.rays;
    v.supersample = settings.supersample;
    v.jitter = settings.jitter && settings.supersample > 1;
    v.depth = depth;
    v.depthIn = depthIn;
    v.stopAlpha = stopAlpha;
    v.depthAlphas = depthAlphas;
    v.viewDirection = setup.viewDirection;
    v.rayStartDepth = setup.rayStartDepth;
    v.depthScale = static_cast<float>(setup.frame.scale);
    return v;
}

/// The values a frame's transfer function spans (FrameSetup::rangeLo, rangeHi): `range`, else
/// the field's whole range; under a log scale a range from 0 or below starts at min(hi / 10^4,
/// 1) (ParaView's AdjustRangeForLog). A range the log scale refuses (hi <= 0) is returned as
/// given (makeFrameSetup refuses it).
std::pair<float, float> frameValueRange(const PreparedMesh& mesh, const RenderSettings& settings);

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

/// One rank's share of a data-parallel frame (RenderResult::ranks).
struct RankFrameStats {
    double frameSeconds = 0.0;      ///< its piece's frame (both passes)
    double compositeSeconds = 0.0;  ///< its part of the compositing
    std::uint64_t bytesSent = 0;    ///< bytes it sent compositing
    std::uint64_t samples = 0;      ///< samples its rays took
    std::uint64_t cells = 0;        ///< cells it holds (its piece's, with the ghosts)
    /// Pixels it rendered again, where its rays stopped behind other ranks' light (the
    /// compositing's second pass).
    std::uint64_t rerenderedPixels = 0;
    std::uint64_t peakHostBytes = 0;  ///< the most host memory its process has held so far
};

/// A rendered frame: image, per-pixel sample counts, statistics.
struct RenderResult {
    Image image;
    std::vector<std::uint32_t> sampleCounts;  ///< per pixel, row-major
    /// Depth out (RenderSettings::depthAlpha > 0): per pixel, row-major, the distance along the
    /// view direction in the file's units (the nearest over the pixel's rays); else empty.
    std::vector<float> depth;
    RenderStats stats;
    FrameSetup setup;
    /// A data-parallel frame: per rank (every rank's, in rank order), on every rank; stats then
    /// sum the ranks' counters. Empty for one process.
    std::vector<RankFrameStats> ranks;
};

}  // namespace uvr

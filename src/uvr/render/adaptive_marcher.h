// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>
#include <cstdint>

#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/macro_grid.h"
#include "uvr/accel/seed_grid.h"
#include "uvr/render/ray_cells.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/tf/range_stats.h"

namespace uvr {

/// What a ray needs to know about a partition under the current transfer function.
struct PartitionShading {
    float maxOpacity = 0.f;  ///< 0: the partition is invisible and can be skipped
    float step = 0.f;        ///< sample spacing inside the partition
    /// With macrocells (error-bound rule): march the partition by its macrocells' steps and
    /// skips instead of its own step (macroCellsPay).
    bool byMacroCells = false;
};

/// How the partition integrator chooses each partition's step.
enum class StepRule : std::uint8_t {
    /// From a bound on the integration error per opacity unit (errorBoundStep; the default).
    ErrorBound,
    /// Morrical et al. 2019, Sec. 2.4: from the colour variance over the partition's value range,
    /// normalised over the visible partitions (adaptiveStep).
    Variance,
};

/// Everything the step rules need besides a partition's own statistics.
struct StepRuleParams {
    StepRule rule = StepRule::ErrorBound;
    bool adaptive = true;  ///< false: every partition at s1
    float s1 = 1.f;        ///< smallest step (the reference's spacing)
    float s2 = 16.f;       ///< largest step
    float power = 2.f;     ///< Variance: power p >= 1 of the step formula
    /// ErrorBound: the optical depth error allowed per opacity unit (see errorBoundStep).
    float tolerance = 0.05f;
    /// ErrorBound: value change per table entry, (hi - lo) / (count - 1) of the baked table.
    float valuePerEntry = 1.f;
    /// Shaded frames and those with a gradient opacity (shadeLit): a visible partition or
    /// macrocell of maximum opacity a steps at most max(litMinStep, litStepScale / a).
    /// Infinite (frames that read no gradient): no limit.
    float litStepScale = INFINITY;
    float litMinStep = 0.f;
};

/// Adaptive step (Morrical et al. 2019, Sec. 2.4): s = max(s1 + (s2 - s1) |min(v, 1) - 1|^p, s1)
/// for normalised colour variance v (v >= 1 gives s1, v = 0 gives s2).
UVR_HOST_DEVICE inline float adaptiveStep(float v, float s1, float s2, float p) {
    const float x = fabsf((v < 1.f ? v : 1.f) - 1.f);
    const float s = s1 + (s2 - s1) * powf(x, p);
    return s > s1 ? s : s1;
}

/// Where the error bound asks for steps below s1, it asks more than it needs there (the bound
/// adds up the worst case of every cell a step crosses): a step goes below s1 only where
/// kFinerStepSlack times the bound's step is still below s1 (16: the default transfer function
/// keeps s1 on every shared mesh but a few macrocells; PERFORMANCE.md, "Steps below s1 where
/// the bound asks (issue 29), CPU").
inline constexpr float kFinerStepSlack = 16.f;

/// The error-bound step where the bound's h is below s1: s1 where kFinerStepSlack h reaches
/// s1, else s1 / 2 where it reaches s1 / 2, else s1 / 4 (NaN too). In a piece marched at its
/// own step, steps of s1 / 2^n put a sample on every reference grid point it owns, between them
/// the finer ones.
UVR_HOST_DEVICE inline float finerStep(float h, float s1) {
    const float relaxed = kFinerStepSlack * h;
    if (relaxed >= s1) return s1;
    return relaxed >= 0.5f * s1 ? 0.5f * s1 : 0.25f * s1;
}

/// Error-bound step (issue 11, beyond the paper): with pre-integration the segment between two
/// samples is exact while the scalar is linear between them; the error comes from its deviation
/// from linear, at most spread * h / 4 over a step h when the directional derivative along the
/// ray varies by at most `spread` (the spread of the partition's cell gradients). Through the
/// transfer function, whose optical depth per unit (and emission) changes by at most maxRate
/// per table entry over the partition's value range, that is an optical depth error of at most
/// maxRate / valuePerEntry * spread * h / 4 per opacity unit. The step keeps it at the
/// tolerance: h = 4 tolerance valuePerEntry / (maxRate spread), clamped to s2. A linear field
/// (spread 0) or a transfer function constant over the range (maxRate 0) gets s2; a
/// cell-centred field (infinite spread) s1.
///
/// Below s1 (finerStep): where even kFinerStepSlack h is below s1, the bound is broken by more
/// than that factor at s1 (narrow bands and steps of the transfer function where cells are
/// smaller than s1, which the reference's s1 misses too), and the step is s1 / 2 or s1 / 4.
UVR_HOST_DEVICE inline float errorBoundStep(float maxRate, float spread, const StepRuleParams& r) {
    if (!(maxRate > 0.f) || !(spread > 0.f)) return r.s2;
    if (!(spread < INFINITY)) return r.s1;
    const float h = 4.f * r.tolerance * (r.valuePerEntry / maxRate) / spread;
    if (h >= r.s1) return h < r.s2 ? h : r.s2;
    return h > 0.f ? finerStep(h, r.s1) : r.s1;  // 0 or NaN: a range of zero width
}

/// The longest step of a visible region of maximum opacity a in a shaded frame (StepRuleParams::
/// litStepScale): the rules above see the transfer function and the field's gradients, not the
/// light, and where the field is nearly flat its normals (and so its light) change from cell to
/// cell however slowly the value does. A step of optical depth at most a h / u carries at most
/// that share of the pixel, and its light may be anywhere in [ambient, ambient + diffuse +
/// specular] (the light's rate, diffuse + specular sqrt(power), bounds how far it moves): so h
/// <= kLitError u / (rate a), here litStepScale / a, keeps that error at kLitError, and never
/// below litMinStep (3 s1, which kept Blunt Fin's freestream). A gradient opacity's scale, as
/// noisy, adds its largest value to the rate (setupFrame). docs/METHOD.md, "The adaptive step
/// rule in shaded frames".
UVR_HOST_DEVICE inline void shadeLit(PartitionShading& s, const StepRuleParams& r) {
    if (!(s.maxOpacity > 0.f) || !(r.litStepScale < INFINITY)) return;
    float h = r.litStepScale / s.maxOpacity;
    h = h > r.litMinStep ? h : r.litMinStep;
    s.step = s.step < h ? s.step : h;
}

/// Shading of one partition: its maximum opacity (0: skipped) and step. ErrorBound:
/// errorBoundStep from the range statistics and the partition's gradient spread. Variance
/// (Morrical et al. 2019, Sec. 2.1, 2.4): the variance normalised by the minimum lo and maximum
/// hi over the visible partitions (1 when they are all equal and positive), invisible partitions
/// at v = 0 (s2), and the adaptive step; shaded, at most shadeLit's step. Every step is s1 when
/// adaptive is false. Shared by the CPU loop and the CUDA kernel.
UVR_HOST_DEVICE inline PartitionShading shadePartition(const RangeStats& st, float spread, float lo,
                                                       float hi, const StepRuleParams& r) {
    if (!r.adaptive) return {st.maxOpacity, r.s1};
    PartitionShading s{st.maxOpacity, r.s2};
    if (r.rule == StepRule::ErrorBound) {
        if (st.maxOpacity > 0.f) s.step = errorBoundStep(st.maxRate, spread, r);
    } else {
        float v = 0.f;
        if (st.maxOpacity > 0.f)
            v = hi > lo ? (st.variance - lo) / (hi - lo) : (hi > 0.f ? 1.f : 0.f);
        s.step = adaptiveStep(v, r.s1, r.s2, r.power);
    }
    shadeLit(s, r);
    return s;
}

/// Shading of one macrocell under the error-bound rule: transparent when no tetrahedron with a
/// value overlaps it, else shadePartition over its value range and gradient spread; at the
/// mesh's boundary at most s1 (MacroCell::atBoundary).
UVR_HOST_DEVICE inline PartitionShading shadeMacroCell(const MacroCell& cell,
                                                       const TfRangeView& range,
                                                       const StepRuleParams& r) {
    if (cell.empty()) return {0.f, r.s2};
    PartitionShading s =
        shadePartition(range.query(cell.valueMin, cell.valueMax), cell.gradientSpread, 0.f, 0.f, r);
    if (cell.atBoundary && s.step > r.s1) s.step = r.s1;
    return s;
}

/// Shading of a partition or macrocell holding NaN values: at least the NaN opacity nanAlpha, so
/// visible NaN is never skipped (value ranges leave NaN out); and, when anything in it is
/// visible, the smallest step s1, as at the mesh's boundary: the NaN region's edge is a jump
/// (to the NaN colour, or to nothing) that neither the value range nor the gradient spread shows.
UVR_HOST_DEVICE inline void shadeNan(PartitionShading& s, float nanAlpha, float s1) {
    if (nanAlpha > s.maxOpacity) s.maxOpacity = nanAlpha;
    if (s.maxOpacity > 0.f) s.step = s1;
}

/// Longest step, in s1, in a partition or macrocell an isosurface crosses (shadeIso).
inline constexpr float kIsoMaxStep = 4.f;

/// Shading of a partition or macrocell whose value range [lo, hi] holds an iso value: visible
/// (never skipped) and stepped at most kIsoMaxStep s1. A step that crosses a surface is bisected
/// to within s1 (bisectIso), so the surface lies where the reference's samples put it; what a
/// step can still miss is a fold of the surface thinner than the step (a ray grazing it: a
/// silhouette moves in by about step^2 / (8 r) for a surface of curvature radius r).
UVR_HOST_DEVICE inline void shadeIso(PartitionShading& s, float lo, float hi, const IsoView& iso,
                                     float s1) {
    if (!iso.within(lo, hi)) return;
    for (int i = 0; i < iso.count; ++i)
        s.maxOpacity =
            iso.surfaces[i].opacity > s.maxOpacity ? iso.surfaces[i].opacity : s.maxOpacity;
    const float longest = kIsoMaxStep * s1;
    s.step = s.step < longest ? s.step : longest;
}

/// The macrocells' layout and their shading for the current transfer function.
struct MacroShadingView {
    const PartitionGrid* grids = nullptr;       ///< per partition; null: no macrocells
    const PartitionShading* shading = nullptr;  ///< per macrocell (shadeMacroCell)
};

/// A partition steps by its macrocells only where that cuts its samples to at most this
/// fraction: a macrocell's sample cost about 2.3x a partition's on the H100 (12M multiscale box,
/// narrow band: 63M samples in 18 ms against 110M in 14 ms; the skips and the long steps, located
/// from seeds, diverge within a warp; docs/METHOD.md, "Macrocells").
inline constexpr float kMacroSampleFraction = 0.5f;

/// Samples per unit length a partition with grid g takes when it marches by its macrocells
/// (`cells`: the shading of every macrocell): 1 / step in each visible macrocell, none in a
/// transparent one, averaged over the grid.
UVR_HOST_DEVICE inline float macroSampleDensity(const PartitionGrid& g,
                                                const PartitionShading* cells) {
    const std::uint32_t n = g.dims[0] * g.dims[1] * g.dims[2];
    float samples = 0.f;
    for (std::uint32_t c = 0; c < n; ++c) {
        const PartitionShading& cell = cells[g.first + c];
        if (cell.maxOpacity > 0.f) samples += 1.f / cell.step;
    }
    return samples / static_cast<float>(n);
}

/// Whether a visible partition with shading `partition` pays to march by its macrocells, whose
/// macroSampleDensity is `density`: against the partition's own step's.
UVR_HOST_DEVICE inline bool macroCellsPay(float density, const PartitionShading& partition) {
    if (!(partition.maxOpacity > 0.f) || !(partition.step > 0.f)) return false;
    return density <= kMacroSampleFraction / partition.step;
}

/// Steps longer than this many s1 start their point location from the partition's seed grid
/// instead of the previous sample's tetrahedron: a walk from the previous sample crosses about
/// three tetrahedra per s1, a walk from the seed about as many whatever the step (PERFORMANCE.md).
inline constexpr float kLongStep = 2.f;

/// Scene for the partition integrator: the reference scene plus the partitions and their
/// per-transfer-function shading.
struct PartitionSceneView {
    SceneView base;
    KdView kd;
    /// The tree the samples that walks and seeds do not locate search (buildCellTree).
    BvhView cells;
    SeedGridView seeds;  ///< per-partition walk starts; without them long steps search the tree
    const PartitionShading* shading = nullptr;
    /// Macrocells (null grids: none): when set, each sample's step is its macrocell's, and
    /// transparent macrocells are skipped like transparent partitions.
    MacroShadingView macro;
    bool skipTransparent = true;  ///< skip partitions (and macrocells) whose maximum opacity is 0
    float longStep = kLongStep;   ///< steps above this many s1 do not walk from the previous sample
};

/// A long step from the run's last sample to the sample at kSample (in tetrahedron tet) crosses
/// an isosurface (an odd number of them): probes by bisection, each located by a walk from the
/// last one found, narrow the crossing to within s1, and the probes before it join the run as
/// samples (the one just past it too), so the surface lies where the reference's samples put
/// it, to within s1, whatever the step. Not inlined: only frames with isosurfaces call it, at
/// the steps that cross one (inlined, with withIsos, the 100M isosurface frames got slower on
/// the H100: PERFORMANCE.md, "Isosurfaces: what the surfaces' code costs a frame with no
/// surface").
template <bool kNative, bool kLit>
UVR_HOST_DEVICE UVR_NOINLINE void bisectIso(const PartitionSceneView& scene, const Ray& ray,
                                            float kSample, float k1, std::uint32_t tet,
                                            SampleSegments<kLit, true>& segments,
                                            RayCounters& counters, Vec4f& acc) {
    const TetLocator& locator = scene.base.locator;
    const MarchParams& params = scene.base.params;
    const float s1 = params.step;
    const IsoView& iso = params.iso;
    float lo = segments.kLast, hi = kSample, vLo = segments.vLast;
    bool haveHi = false;  // a probe found at hi (else hi is the sample itself)
    float vHi = 0.f;
    Vec3f gradHi(0.f);
    SamplePoint atHi;
    float bary[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};  // no Newton guess for a native cell
    std::uint32_t from = tet;
    while (hi - lo > 1.f) {
        const float mid = floorf(0.5f * (lo + hi) + 0.5f);
        if (mid <= lo || mid >= hi) break;
        ++counters.samples;
        const Vec3f q = ray.at(mid * s1);
        std::uint32_t found = locator.walk<kNative>(q, from, bary, counters.locate);
        if (found == kNoTet)
            found = locator.search<kNative>(scene.cells, 0, q, bary, counters.locate);
        if (found == kNoTet) break;  // a hole in the mesh: the step's linear reading stands
        from = found;
        const float vMid = locator.mesh.interpolate<kNative>(found, bary);
        const Vec3f gradMid = sampleGradient<kNative, kLit>(params, locator.mesh, found, bary);
        if (iso.crossesOdd(vLo, vMid)) {  // the crossing lies before mid
            hi = mid, vHi = vMid, gradHi = gradMid, atHi = SamplePoint(found, bary), haveHi = true;
        } else {  // after it: the run goes on to mid
            segments.add(
                scene.base.tf, mid, k1, true, vMid, s1, params.opacityUnit, acc,
                lightAt<kLit>(params.light, params.gradientOpacity, found, gradMid, ray.dir),
                SamplePoint(found, bary));
            lo = mid, vLo = vMid;
        }
    }
    if (haveHi)
        segments.add(
            scene.base.tf, hi, k1, true, vHi, s1, params.opacityUnit, acc,
            lightAt<kLit>(params.light, params.gradientOpacity, atHi.cell, gradHi, ray.dir), atHi);
}

/// Whether the ray can meet an isosurface: some partition it crosses (in its clipped span, in
/// front of ray.tMax, through the partition's shrunk box) holds an iso value in its value range.
/// A ray that cannot is marched without the surfaces' code (isoRaySplit): every sample it takes
/// lies in a partition holding no iso value, so no step between two of its samples (the field
/// continuous, linear in each cell) and no stretch to the mesh's boundary crosses one, and
/// marchPartitions' surface calls never run on it.
UVR_HOST_DEVICE inline bool mayMeetIsosurface(const PartitionSceneView& scene, const Ray& ray) {
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float tEnter = 0.f, tExit = INFINITY;
    if (scene.kd.partitionCount == 0 || !intersectBox(scene.kd.bounds, ray.org, inv, tEnter, tExit))
        return false;
    const MarchParams& params = scene.base.params;
    if (params.clip.active() && !params.clip.restrict(ray.org, ray.dir, inv, tEnter, tExit))
        return false;
    if (ray.tMax < tExit) tExit = ray.tMax;
    if (!(tEnter <= tExit)) return false;
    KdLeafIterator leaves(tEnter, tExit);
    std::uint32_t p = 0;
    float t0 = 0.f, t1 = 0.f;
    bool meets = false;
    while (!meets && leaves.next(scene.kd, ray, inv, p, t0, t1)) {
        const KdPartition& part = scene.kd.partitions[p];
        meets = part.cellCount > 0 && intersectBox(part.box, ray.org, inv, t0, t1) &&
                params.iso.within(part.valueMin, part.valueMax);
    }
    return meets;
}

/// Partition integrator (Morrical et al. 2019, Sec. 2.3-2.4): walks the k-d partitions front to
/// back in exact order; skips unoccupied space (outside the shrunk boxes) and, when asked,
/// partitions with zero maximum opacity; marches each visited partition with its own step s,
/// locating samples among the partition's cells and integrating between consecutive samples
/// (SampleSegments; point samples with opacity correction when params.preintegrated is off);
/// stops early once opaque: at `stop` (kSceneStop: at params.terminationAlpha).
///
/// Sample placement: a partition's piece of the ray owns the reference grid points
/// t = k * s1 for k in [K0, K1); its samples sit at (K0 + j * s / s1) * s1 and each one stands
/// for the distance to the next (the last one only up to K1 * s1). So with s == s1 the samples
/// are exactly the reference marcher's, and with larger steps the distances still add up to the
/// piece's length: no partition crossing gains or loses optical depth.
///
/// With macrocells (scene.macro) the step is chosen per sample instead: the step of the
/// macrocell the sample lies in, ending at most at the first grid point past the macrocell (so
/// a long step never reaches deep into a macrocell that needs short ones); a sample in a
/// transparent macrocell is not located: the run of samples ends there (as at a skipped
/// partition) and the next sample is the first grid point past the macrocell.
///
/// At the mesh's boundary (issue 29) long steps behave as the reference's: every piece has a
/// sample at its last grid point K1 - 1 (the run's last share is one s1, never a long step past
/// a curved boundary to the end of the piece's box), and a sample outside the mesh is followed
/// by one s1 on (or by the first grid point past its seed-grid cell when that holds no cell), so
/// a grazing ray's short chord is not stepped over.
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
UVR_HOST_DEVICE inline Vec4f marchPartitions(const PartitionSceneView& scene, const Ray& ray,
                                             RayCounters& counters, float stop = kSceneStop) {
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float tEnter = 0.f, tExit = INFINITY;
    if (scene.kd.partitionCount == 0 || !intersectBox(scene.kd.bounds, ray.org, inv, tEnter, tExit))
        return acc;
    const ClipView& clip = scene.base.params.clip;
    [[maybe_unused]] bool cut0 = false, cut1 = false;  // the span's ends on the clip's faces
    [[maybe_unused]] Vec3f n0, n1;
    if (kSurf && clip.surface) {
        if (!clip.restrictFaces(ray.org, ray.dir, inv, tEnter, tExit, cut0, n0, cut1, n1))
            return acc;
    } else if (clip.active() && !clip.restrict(ray.org, ray.dir, inv, tEnter, tExit)) {
        return acc;
    }
    if (ray.tMax < tExit) tExit = ray.tMax, cut1 = false;  // depth in: opaque geometry there
    // A data-parallel frame: this rank's piece of the span (its k-d tree is the whole tree's
    // subtree there, so the partitions' pieces are one process's).
    bool pieceStart = false, pieceEnd = false;
    const float tSpan = tEnter, tSpanEnd = tExit;  // where one process's span starts and ends
    if (!scene.base.params.piece.narrow(ray.org, inv, tEnter, tExit, pieceStart, pieceEnd))
        return acc;
    if (pieceStart) cut0 = false;
    if (pieceEnd) cut1 = false;
    if (!(tEnter <= tExit)) return acc;
    const TetLocator& locator = scene.base.locator;
    const float s1 = scene.base.params.step;
    const float unit = scene.base.params.opacityUnit;
    const float stopAlpha = stop < 0.f ? scene.base.params.terminationAlpha : stop;
    const TfTableView& tf = scene.base.tf;
    const bool preintegrated = scene.base.params.preintegrated;
    const Lighting lighting = kernelLighting<kLit, kSurf>(scene.base.params);
    SampleSegments<kLit, kSurf> segments;
    const RaySurfaces surfaces(scene.base.params.iso, lighting, ray.dir,
                               rayDepthAlpha(scene.base.params, counters), locator.mesh);
    segments.setIsos(surfaces);
    PointIsos<kSurf> pointIsos;
    std::uint32_t lastInside = kNoTet;  // the tetrahedron of the last sample inside the mesh
    // Where a run may start at the mesh's boundary (sampleAtBoundary): after the grid position
    // kRunFrom, outside the mesh when runFromOutside (else the span's start), while runFromValid
    // (no sample inside and nothing skipped since; a data-parallel piece's start takes them from
    // the piece before's last grid point, below).
    float kRunFrom = tEnter / s1;
    bool runFromOutside = false, runFromValid = !pieceStart;
    bool skipped = false;  // a transparent partition or macrocell since a sample
    const auto locateFrom = [&](Vec3f q, std::uint32_t from, float* b, LocateCounters& c) {
        std::uint32_t found = locator.walk<kNative>(q, from, b, c);
        if (found == kNoTet) found = locator.search<kNative>(scene.cells, 0, q, b, c);
        return found;
    };
    if constexpr (kSurf) {  // the cut face in front: nothing else shows
        bool hit = false;
        if (cut0)
            callOnCopies(counters, acc, [&](RayCounters& c, Vec4f& a) {
                hit = cutFace<kNative>(locateFrom, scene.base.params, locator.mesh, tf, ray, tEnter,
                                       n0, kNoTet, c, a);
            });
        if (hit) return acc;
    }
    std::uint32_t tet = kNoTet;
    float bary[4] = {0.f, 0.f, 0.f, 0.f};
    if (pieceStart && preintegrated) {
        // A data-parallel piece that may start inside a run: the piece before's last sample, one
        // grid point before this piece's first, gives the run's slope (SampleSegments::lead; a
        // first sample taken later, or outside the mesh, does not continue it).
        const float kFirst = ceilf(tEnter / s1);
        if (kFirst - 1.f >= ceilf(tSpan / s1)) {
            ++counters.samples;
            float b[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};
            std::uint32_t found = locateFrom(ray.at(kFirst * s1), kNoTet, b, counters.locate);
            const bool firstIn = found != kNoTet;
            if (firstIn) found = locateFrom(ray.at((kFirst - 1.f) * s1), found, b, counters.locate);
            if (found != kNoTet)
                segments.lead(kFirst - 1.f, true, locator.mesh.interpolate<kNative>(found, b));
            // Where that sample lies outside the mesh, a run starting in this piece starts at the
            // boundary after it (sampleAtBoundary), as one process's does.
            if (!firstIn)
                found = locateFrom(ray.at((kFirst - 1.f) * s1), kNoTet, b, counters.locate);
            if (found == kNoTet)
                kRunFrom = kFirst - 1.f, runFromOutside = true, runFromValid = true;
        } else {
            // No grid point of the span lies before the piece: one process's run may start at
            // the span's start, in the piece before (its ghost cells hold it).
            kRunFrom = tSpan / s1, runFromValid = true;
        }
    }
    // One loop whose every iteration takes a sample, skips a transparent macrocell or moves to
    // the next partition, so GPU threads of a warp crossing partition boundaries at different
    // samples stay together. The loop leaves only through its condition (no break or return
    // inside): a branch that can leave the loop has its reconvergence point after the loop, and
    // warps whose threads split there ran one thread at a time (measured on the H100: 1.2
    // active threads per instruction, 12x the reference marcher's time at the same samples).
    KdLeafIterator leaves(tEnter, tExit);
    std::uint32_t p = 0;
    // A run whose share ends before the next sample (empty space or the next rank's piece
    // follows), or before the span's end, ends at the mesh's boundary before its share's end
    // kEnd (sampleAtBoundary): unless a transparent partition or macrocell was skipped, no
    // partition holds kEnd (else a sample would be there), so it lies outside the mesh, and a
    // run after it starts at the boundary, as after an outside sample. After a skip kEnd lies in
    // the skipped part: the run ends there as before (with isosurfaces a surface between its last
    // sample and kEnd is still crossed). The next add() or finish() ends the run.
    const auto endRunAtShare = [&]() {
        if (!skipped || segments.iso)
            callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& acs) {
                sampleAtBoundary<kNative, kLit, kSurf>(locateFrom, scene.base.params, locator, tf,
                                                       ray, lighting, sc.kEnd, true, sc.kLast,
                                                       lastInside, sc.kEnd, sc, c, acs);
            });
        if (!skipped) kRunFrom = segments.kEnd, runFromOutside = true, runFromValid = true;
    };
    float k = 0.f, k1 = 0.f, kStop = 0.f, mPiece = 1.f;
    float kLocated = -INFINITY;  // grid position of the last sample located
    // Outside a non-convex mesh: the grid positions below kOutside lie outside it, before the
    // ray enters it again (outsideUntil, asked at a sample found outside; infinity when the ray
    // never does). They take no point location, and most no sample (below).
    float kOutside = -INFINITY;
    const double entryEps = cellGapEps(scene.base.bounds, tEnter);
    bool marching = true, opaque = false, macro = false;
    // Depth out: the opacity and the end of the stretch of the ray noted last, noted wherever
    // the run composites (after each sample, and where a transparent macrocell ends a run).
    [[maybe_unused]] float aNoted = 0.f, tNoted = tEnter;
    [[maybe_unused]] const float depthAlpha = rayDepthAlpha(scene.base.params, counters);
    auto note = [&](float tNow) {
        if constexpr (kSurf) {
            if (segments.kDepth < INFINITY && !(counters.depth < INFINITY))
                counters.depth = segments.kDepth * s1;
            tNow = fmaxf(tNoted, tNow);
            noteDepth(depthAlpha, aNoted, acc.w, tNoted, tNow, counters);
            aNoted = acc.w, tNoted = tNow;
        }
    };
    while (marching) {
        // The piece's grid points end before K1 (a step of one s1 from K1 - 1 outside the mesh
        // would reach the next partition's first).
        if (!(k < kStop && k < k1)) {
            float t0, t1;
            if (!leaves.next(scene.kd, ray, inv, p, t0, t1)) {
                marching = false;
                continue;
            }
            const KdPartition& part = scene.kd.partitions[p];
            const PartitionShading shade = scene.shading[p];
            ++counters.partitionsVisited;
            if (part.cellCount == 0) continue;
            if (scene.skipTransparent && !(shade.maxOpacity > 0.f)) {
                ++counters.partitionsSkipped;
                runFromValid = false, skipped = true;
                continue;
            }
            // Only the part of [t0, t1) inside the shrunk box can hold cells.
            float c0 = t0, c1 = t1;
            if (!intersectBox(part.box, ray.org, inv, c0, c1)) continue;
            // Reference grid points owned: [K0, K1); the ray's end point belongs to the last
            // piece.
            k = ceilf(c0 / s1);
            k1 = (c1 < t1 || (t1 >= tExit && !pieceEnd)) ? floorf(c1 / s1) + 1.f : ceilf(t1 / s1);
            mPiece = shade.step / s1;  // step in grid units (1 for s1)
            macro = scene.macro.grids && shade.byMacroCells;
            kStop = k1;
            // Pre-integrated steps longer than s1 divide the piece up to its last grid point
            // K1 - 1 evenly into at least two (but no step below s1), and a sample sits there:
            // the piece's last sample owns one s1 as the reference's does, so a run never
            // extends a long step past the mesh's boundary to the piece's end (the end of the
            // shrunk box lies outside a curved boundary; the next sample, in another piece,
            // may be far), and a boundary inside the piece is bisected for as usual. A piece of
            // a linear field is integrated exactly. (Macrocell steps end at the macrocells and
            // at K1 - 1 instead.)
            if (!macro && preintegrated && mPiece > 1.f) {
                const float span = k1 - 1.f - k;
                const float parts = fmaxf(2.f, ceilf(span / mPiece));
                mPiece = fmaxf(1.f, span / parts);
                // Rounding in k += m must neither drop the sample at K1 - 1 nor add one past it.
                kStop = k1 - 1.f + 0.5f * mPiece;
            }
            continue;
        }
        const float kSample = k;
        const Vec3f pos = ray.at(k * s1);
        float kNext = k + mPiece;
        bool endsRun = false;  // the sample ends its run: it owns no distance
        if (macro) {
            const PartitionGrid& g = scene.macro.grids[p];
            std::uint32_t idx[3];
            const PartitionShading cell = scene.macro.shading[macroCellOf(g, pos, idx)];
            const float m = cell.step / s1;
            const bool transparent = scene.skipTransparent && !(cell.maxOpacity > 0.f);
            // The first grid point past the macrocell (at least the next one); not needed for
            // steps of s1.
            const float kPast = transparent || m > 1.f
                                    ? fmaxf(k + 1.f, ceilf(gridCellExit(g, idx, ray.org, inv) / s1))
                                    : k + 1.f;
            if (transparent) {
                // Transparent: the run ends here; the next sample is past the macrocell. After a
                // long step the mesh may have ended before this point (empty macrocells are
                // transparent): the sample is then located as usual, which finds the boundary.
                const bool longGap = preintegrated && segments.started && segments.inside &&
                                     !segments.led && kSample - segments.kLast > 1.f;
                runFromValid = false, skipped = true;
                if (!longGap) {
                    if (preintegrated) {
                        // A run ending here ends at the mesh's boundary where the macrocell
                        // lies outside the mesh (empty macrocells are transparent): a walk from
                        // the run's last cell that leaves the mesh says so.
                        if (segments.started && segments.inside && !segments.led &&
                            kSample <= segments.kEnd) {
                            float b[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};
                            ++counters.samples;
                            if (locator.walk<kNative>(pos, lastInside, b, counters.locate) ==
                                kNoTet)
                                callOnCopies(segments, counters, acc,
                                             [&](auto& sc, RayCounters& c, Vec4f& a) {
                                                 sampleAtBoundary<kNative, kLit, kSurf>(
                                                     locateFrom, scene.base.params, locator, tf,
                                                     ray, lighting, kSample, true, sc.kLast,
                                                     lastInside, k1, sc, c, a);
                                             });
                        }
                        segments.add(tf, kSample, kSample, false, 0.f, s1, unit, acc);
                        note(kSample * s1);
                    }
                    k = kPast;
                    continue;
                }
                endsRun = true;
                kNext = kPast;
            } else {
                kNext = fminf(k + m, kPast);
            }
        }
        ++counters.samples;
        // Point location: a walk from the previous sample's tetrahedron (short steps), else
        // from the seed of the sample's grid cell (none: no cell of the partition is near, the
        // sample is in empty space), else a search of the cell tree (walks stop at boundaries
        // of non-convex meshes and at seams of unshared points).
        const bool walk = kSample - kLocated <= scene.longStep;
        const bool outside = kSample < kOutside;
        kLocated = kSample;
        tet = walk && !outside ? locator.walk<kNative>(pos, tet, bary, counters.locate) : kNoTet;
        bool emptySpace = false;
        if (tet == kNoTet && !outside && scene.seeds.grids) {
            const std::uint32_t seed = scene.seeds.seed(p, pos);
            emptySpace = seed == kNoTet;
            if (!emptySpace) tet = locator.walk<kNative>(pos, seed, bary, counters.locate);
        }
        if (tet == kNoTet && !emptySpace && !outside)
            tet = locator.search<kNative>(scene.cells, 0, pos, bary, counters.locate);
        // Outside the mesh (no seed near, or nothing found): where does the ray enter it again?
        if (tet == kNoTet && !outside)
            kOutside = outsideUntil<kNative>(locator.mesh, scene.cells, ray, kSample, s1, entryEps,
                                             counters.locate);
        const float v = tet == kNoTet ? 0.f : locator.mesh.interpolate<kNative>(tet, bary);
        const Vec3f grad =
            sampleGradient<kNative, kLit>(scene.base.params, locator.mesh, tet, bary);
        const LightFactors light =
            lightAt<kLit>(lighting, scene.base.params.gradientOpacity, tet, grad, ray.dir);
        // Outside the mesh (in the piece's box), a long step could jump over a grazing ray's
        // short chord through the mesh, which the reference's s1 steps see: the next sample is
        // one s1 on, or past the seed grid's cell when no cell of the partition overlaps it.
        // Inside, long steps go on; leaving the mesh is bisected for below.
        if (tet == kNoTet && !endsRun && kNext - kSample > 1.f) {
            kNext = kSample + 1.f;
            if (emptySpace) {
                const PartitionGrid& g = scene.seeds.grids[p];
                std::uint32_t idx[3];
                for (int a = 0; a < 3; ++a) idx[a] = SeedGridView::cellIndex(g, a, pos[a]);
                kNext = fmaxf(kNext, ceilf(gridCellExit(g, idx, ray.org, inv) / s1));
            }
        }
        // Outside, before the ray's next entry into the mesh: on to the last grid position
        // before it. Each position skipped would have stepped one s1 on, outside; the one there
        // is taken, so the step into the mesh is one s1 as before and the picture is the same.
        if (tet == kNoTet && !endsRun && kSample + 2.f < kOutside)
            kNext = fmaxf(kNext, lastOutside(kSample, kOutside));
        // A sample at the piece's last grid point K1 - 1 (see the piece's steps above).
        if (kSample < k1 - 1.f && kNext > k1 - 1.f) kNext = k1 - 1.f;
        const float length = ((kNext < k1 ? kNext : k1) - kSample) * s1;
        k = kNext;
        if (preintegrated) {
            if (segments.started && segments.inside && !segments.led && kSample > segments.kEnd)
                endRunAtShare();
            // A step longer than s1 from inside the mesh to outside it, or back in: the mesh's
            // boundary lies somewhere in the step. Bisect for it with point locations (walks
            // from the inside end) to within s1, so a run ends or starts there to within a
            // reference step instead of a long one (long steps would show the partitions'
            // blocks along the mesh's silhouette).
            const bool in = tet != kNoTet;
            if (segments.started && segments.inside != in && kSample <= segments.kEnd &&
                kSample - segments.kLast > 1.f) {
                float lo = segments.kLast, hi = kSample;  // inside end first when leaving
                float vHi = v;  // entering: the value at hi, the first position found inside
                LightFactors lightHi = light;  // and its light and where it lies
                SamplePoint atHi(tet, bary);
                std::uint32_t from = in ? tet : lastInside;
                float probeBary[4] = {bary[0], bary[1], bary[2], bary[3]};
                while (fabsf(hi - lo) > 1.f) {
                    const float mid = floorf(0.5f * (lo + hi) + 0.5f);
                    if (mid == lo || mid == hi) break;
                    ++counters.samples;
                    const Vec3f q = ray.at(mid * s1);
                    std::uint32_t found =
                        locator.walk<kNative>(q, from, probeBary, counters.locate);
                    if (found == kNoTet)
                        found =
                            locator.search<kNative>(scene.cells, 0, q, probeBary, counters.locate);
                    const float vMid =
                        found == kNoTet ? 0.f : locator.mesh.interpolate<kNative>(found, probeBary);
                    const Vec3f gradMid = sampleGradient<kNative, kLit>(
                        scene.base.params, locator.mesh, found, probeBary);
                    const LightFactors lightMid = lightAt<kLit>(
                        lighting, scene.base.params.gradientOpacity, found, gradMid, ray.dir);
                    if (found != kNoTet) from = found;
                    if ((found != kNoTet) == in) {  // the mid is on the current sample's side
                        hi = mid;
                        vHi = vMid;
                        lightHi = lightMid;
                        atHi = SamplePoint(found, probeBary);
                    } else {
                        // Leaving: the run goes on to the mid.
                        if (found != kNoTet)
                            segments.add(tf, mid, k1, true, vMid, s1, unit, acc, lightMid,
                                         SamplePoint(found, probeBary));
                        lo = mid;
                    }
                }
                // The run starts or ends at the boundary between lo and hi (sampleAtBoundary);
                // entering, its first grid sample is the first position found inside, leaving,
                // the first position found outside ends it.
                if (!in || runFromValid)
                    callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                        sampleAtBoundary<kNative, kLit, kSurf>(
                            locateFrom, scene.base.params, locator, tf, ray, lighting, in ? lo : hi,
                            true, in ? hi : sc.kLast, from, k1, sc, c, a);
                    });
                if (in) runFromValid = false;
                if (in && hi < kSample)
                    segments.add(tf, hi, k1, true, vHi, s1, unit, acc, lightHi, atHi);
                else if (!in)
                    segments.add(tf, hi, k1, false, 0.f, s1, unit, acc);
            }
            // A step longer than s1 inside the mesh across an isosurface: the crossing is
            // bisected for to within s1 (isosurface.h).
            if constexpr (kSurf) {
                if (in && segments.iso && segments.started && segments.inside &&
                    kSample <= segments.kEnd && kSample - segments.kLast > 1.f &&
                    segments.iso->crossesOdd(segments.vLast, v))
                    callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                        bisectIso<kNative, kLit>(scene, ray, kSample, k1, tet, sc, c, a);
                    });
            }
            // A run starts (not after a long step: bisected above) at the mesh's boundary or the
            // span's start, and ends at the boundary (sampleAtBoundary). A run whose share ended
            // before this sample goes on no further.
            // (One call for both: each call site of a function not inlined costs the loop
            // registers on the GPU.)
            const bool runGoesOn = segments.inside && kSample <= segments.kEnd;
            const bool runStarts = in && runFromValid && !runGoesOn;
            const bool runEnds = !in && segments.started && segments.inside && !segments.led &&
                                 kSample <= segments.kEnd && !endsRun;
            if (runStarts || runEnds)
                callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                    sampleAtBoundary<kNative, kLit, kSurf>(
                        locateFrom, scene.base.params, locator, tf, ray, lighting,
                        in ? kRunFrom : kSample, in ? runFromOutside : true,
                        in ? kSample : sc.kLast, in ? tet : lastInside, k1, sc, c, a);
                });
            if (in) lastInside = tet;
            if (in) {
                runFromValid = false;
            } else {
                kRunFrom = kSample, runFromOutside = true, runFromValid = true;
            }
            skipped = false;
            segments.add(tf, kSample, endsRun ? kSample : k1, in, v, s1, unit, acc, light,
                         SamplePoint(tet, bary));
        } else {
            pointIsos.add(scene.base.params, locator.mesh, tf, ray.dir, tet != kNoTet, v,
                          SamplePoint(tet, bary), acc);
        }
        if (!preintegrated && tet != kNoTet) {
            const Vec4f c = tf.sample(v);
            const float a = correctOpacity(c.w, length * light.opacity, unit, tf.law);
            if (a > 0.f) compositeFrontToBack(acc, light.apply(c.xyz()), a);
        }
        note(kSample * s1);
        opaque = acc.w >= stopAlpha;
        marching = !opaque;
    }
    // The span goes on past this piece to a grid point (kClose) in the next rank's piece (else it
    // ends before any: one process's run ends at the span's end, as below).
    const float kClose = ceilf(tExit / s1);
    if (preintegrated && !opaque && pieceEnd && kClose < ceilf(tSpanEnd / s1)) {
        // A run reaching kClose ends its last segment at the sample there, as one process's run
        // does when the next partition is marched (its share is the next piece's).
        if (segments.started && segments.inside && segments.kEnd >= kClose) {
            ++counters.samples;
            const Vec3f q = ray.at(kClose * s1);
            tet = locateFrom(q, lastInside, bary, counters.locate);
            // Outside the mesh: the run ends at the boundary before it.
            if (tet == kNoTet && !segments.led) endRunAtShare();
            const float v = tet == kNoTet ? 0.f : locator.mesh.interpolate<kNative>(tet, bary);
            const Vec3f grad =
                sampleGradient<kNative, kLit>(scene.base.params, locator.mesh, tet, bary);
            segments.add(
                tf, kClose, kClose, tet != kNoTet, v, s1, unit, acc,
                lightAt<kLit>(lighting, scene.base.params.gradientOpacity, tet, grad, ray.dir),
                SamplePoint(tet, bary));
        } else {
            // The run's share ends before the next piece (a skipped partition or empty space
            // follows it): one process's next sample ends it there, so this piece does.
            if (segments.started && segments.inside && !segments.led) endRunAtShare();
            segments.finish(tf, s1, unit, acc);
        }
        note(tExit);
    } else if (preintegrated && !opaque) {
        // A run reaching the span's end (the bounds' face, a clip plane, depth in) ends at the
        // mesh's boundary or the end, whichever comes first; a run whose share ends before the
        // end ends at the boundary before its share's end.
        if (segments.started && segments.inside && !segments.led) {
            if (segments.kEnd < tSpanEnd / s1)
                endRunAtShare();
            else
                callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                    sampleAtBoundary<kNative, kLit, kSurf>(locateFrom, scene.base.params, locator,
                                                           tf, ray, lighting, tSpanEnd / s1, true,
                                                           sc.kLast, lastInside, sc.kEnd, sc, c, a);
                });
        }
        segments.finish(tf, s1, unit, acc);
        note(tSpanEnd);
    }
    if constexpr (kSurf) {  // the cut face behind the volume
        if (cut1 && !opaque)
            callOnCopies(counters, acc, [&](RayCounters& c, Vec4f& a) {
                cutFace<kNative>(locateFrom, scene.base.params, locator.mesh, tf, ray, tExit, n1,
                                 lastInside, c, a);
            });
    }
    return acc;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>
#include <cstdint>

#include "uvr/accel/point_locator.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/render/camera.h"
#include "uvr/render/ray_cells.h"
#include "uvr/render/scene_view.h"
#include "uvr/render/segment_integral.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Opacity of a sample taken over distance `step` for a TF opacity `alpha` defined per `unit`
/// under a law (opacity correction): 1 - exp(-alpha step / unit) (attenuation), 1 - (1 -
/// alpha)^(step / unit) (transmittance).
UVR_HOST_DEVICE inline float correctOpacity(float alpha, float step, float unit, OpacityLaw law) {
    if (alpha <= 0.f) return 0.f;
    if (law == OpacityLaw::Attenuation) return -expm1f(-(alpha < 1.f ? alpha : 1.f) * step / unit);
    if (alpha >= 1.f) return 1.f;
    return 1.f - powf(1.f - alpha, step / unit);
}

/// Front-to-back "over" compositing of a straight colour with corrected opacity a into the
/// premultiplied accumulator.
UVR_HOST_DEVICE inline void compositeFrontToBack(Vec4f& acc, Vec3f rgb, float a) {
    const float w = (1.f - acc.w) * a;
    acc.x += w * rgb.x;
    acc.y += w * rgb.y;
    acc.z += w * rgb.z;
    acc.w += w;
}

/// Where a sample lies: its cell (kNoTet: outside the mesh) and its local coordinates there
/// (TetMeshView::interpolate's). The isosurfaces' normals are computed from it only where a
/// surface is crossed (SampleSegments, PointIsos), not at every sample.
struct SamplePoint {
    std::uint32_t cell = kNoTet;
    float bary[4] = {0.f, 0.f, 0.f, 0.f};

    UVR_HOST_DEVICE SamplePoint() {}
    UVR_HOST_DEVICE SamplePoint(std::uint32_t c, const float b[4]) : cell(c) {
        for (int i = 0; i < 4; ++i) bary[i] = b[i];
    }
    /// The field's gradient there (TetMeshView::gradient; 0 outside the mesh).
    UVR_HOST_DEVICE Vec3f gradient(const TetMeshView& mesh, bool smooth) const {
        return cell == kNoTet ? Vec3f(0.f) : mesh.gradient(cell, bary, smooth);
    }
};

/// The normals of the isosurfaces crossed between two samples lying at a and b: their
/// gradients, read at the first crossing only, interpolated to the crossing's fraction f.
struct CrossingNormals {
    Vec3f ga{0.f, 0.f, 0.f}, gb{0.f, 0.f, 0.f};
    bool read = false;

    UVR_HOST_DEVICE Vec3f at(const TetMeshView& mesh, bool smooth, const SamplePoint& a,
                             const SamplePoint& b, float f) {
        if (!read) {
            ga = a.gradient(mesh, smooth);
            gb = b.gradient(mesh, smooth);
            read = true;
        }
        return ga + (gb - ga) * f;
    }
};

/// What a ray's isosurfaces need where one is crossed, set once per ray (SampleSegments::setIsos)
/// and read through one pointer only there: a sample's registers hold none of it.
struct RaySurfaces {
    const IsoView* iso = nullptr;       ///< the isosurfaces (null: none)
    const TetMeshView* mesh = nullptr;  ///< their normals' mesh
    Lighting surface;                   ///< their lighting (surfaceLighting)
    Vec3f dir{0.f, 0.f, 1.f};           ///< the ray's direction
    float depthAlpha = 0.f;             ///< depth out (the ray's: rayDepthAlpha)

    /// The isosurfaces of `isos` lit by `l` along a ray of direction d with the gradients of
    /// mesh m, and the opacity whose depth is asked for.
    UVR_HOST_DEVICE RaySurfaces(const IsoView& isos, const Lighting& l, Vec3f d, float alpha,
                                const TetMeshView& m)
        : iso(isos.active() ? &isos : nullptr),
          mesh(&m),
          surface(surfaceLighting(l)),
          dir(d),
          depthAlpha(alpha) {}
};

/// Pre-integration for the sample-based methods (issue 11): the segment between two consecutive
/// samples inside the mesh, at grid positions k (in units of s1), is integrated with the scalar
/// running linearly from one sample's value to the next (segment::integrate), so a
/// transfer-function feature between two samples is integrated, never missed, and no step is
/// too long where the field is linear. Each sample owns the distance to the next sample, as a
/// point sample does: the last sample of a run inside the mesh (before a sample that found no
/// cell, a gap between the pieces of the ray that partitions own, or the end of the ray) owns
/// the distance up to the next sample or the end of its piece, over which the run's last slope
/// is extended (its value held for a run of one sample). So a run of n samples covers the same
/// distance as n point samples, a linear field is integrated exactly, and with equal steps the
/// partition integrator takes exactly the reference's segments. kLit false: without the lights
/// (an unshaded kernel holds none of their registers); kSurf false: without isosurfaces and
/// depth. With isosurfaces (setIsos), a segment crossing one is integrated up to the crossing
/// (where the linear value meets it), the surface composited there, lit by the gradient
/// interpolated between the two samples', and the rest integrated after it. Those gradients are
/// computed only there, from where the samples lie (SamplePoint): a frame with isosurfaces
/// reads no gradient at the samples between them.
template <bool kLit = true, bool kSurf = kLit>
struct SampleSegments {
    float kLast = 0.f;             ///< grid position of the last sample
    float kEnd = 0.f;              ///< end of the piece of the ray the last sample belongs to
    float vLast = 0.f;             ///< its value (when inside)
    LightFactors light;            ///< its light (when inside; the identity unlit)
    SamplePoint atLast;            ///< where it lies (with isosurfaces: their normals)
    const IsoView* iso = nullptr;  ///< the isosurfaces (null: none)
    const RaySurfaces* surfaces = nullptr;  ///< the rest of what they need (setIsos)
    /// Depth out: the grid position where an isosurface took the opacity to depthAlpha
    /// (infinity: none did); the marchers prefer it to their coarser stretches.
    float kDepth = INFINITY;
    float kPrev = 0.f;     ///< grid position of the sample before it in the run
    float vPrev = 0.f;     ///< its value
    bool inRun = false;    ///< the sample before the last one is in the last one's run
    bool inside = false;   ///< the last sample found a cell
    bool started = false;  ///< a sample was taken
    bool led = false;      ///< the last sample is a lead (lead()): no segment up to the next

    /// Isosurfaces to composite between samples (kSurf only): `r`, which must outlive the
    /// marching.
    UVR_HOST_DEVICE void setIsos(const RaySurfaces& r) {
        if constexpr (kSurf) {
            iso = r.iso;
            surfaces = &r;
        }
    }

    /// A data-parallel piece's start: the sample at grid position k just before the piece's
    /// first, found in a cell (`in`) with value v, which the piece before integrated. It only
    /// gives the run that the first sample continues its last slope (endRun): one process's run
    /// holds it. The next add() integrates nothing up to it (the segment is the other piece's).
    UVR_HOST_DEVICE void lead(float k, bool in, float v) {
        kLast = k;
        kEnd = k + 1.f;
        vLast = v;
        inside = in;
        started = true;
        led = true;
    }

    /// Adds the sample at grid position k of a piece of the ray that ends at kPieceEnd (the
    /// next piece continues it when it starts there); `in`: it found a cell, with value v,
    /// light f (gradient shading; the segment from the last sample is lit by the mean of their
    /// lights, the run's last share by its last sample's), lying at `at` (isosurfaces).
    UVR_HOST_DEVICE UVR_INLINE void add(const TfTableView& tf, float k, float kPieceEnd, bool in,
                                        float v, float s1, double unit, Vec4f& acc,
                                        LightFactors f = {}, const SamplePoint& at = {}) {
        const bool goesOn = started && inside && in && k <= kEnd;
        if (led) {
            // From a lead sample: the segment (or the run's end) is the piece before's.
        } else if (goesOn) {
            bool done = false;
            if constexpr (kSurf) {
                // (Called only where a surface is crossed: a call at every sample cost the
                // isosurfaces' kernels most of their time.)
                if (iso && iso->crosses(vLast, v)) {
                    // On copies, as callOnCopies runs the other surface calls.
                    SampleSegments s = *this;
                    Vec4f a = acc;
                    s.withIsos(tf, v, k, s1, unit, light.mean(f), at, a);
                    kDepth = s.kDepth, acc = a;
                    done = true;
                }
            }
            if (!done)
                integrateLit<kLit>(tf, vLast, v, double(k - kLast) * s1, unit, light.mean(f), acc);
        } else if (started && inside) {  // the run ends
            endRun(tf, (k < kEnd ? k : kEnd) - kLast, s1, unit, acc);
        }
        inRun = goesOn;
        kPrev = kLast;
        vPrev = vLast;
        kLast = k;
        kEnd = kPieceEnd;
        vLast = v;
        if constexpr (kLit) light = f;
        if constexpr (kSurf) atLast = at;
        inside = in;
        started = true;
        led = false;
    }
    /// Ends the last run at the end of the ray (a lead sample's run is the piece before's).
    UVR_HOST_DEVICE void finish(const TfTableView& tf, float s1, double unit, Vec4f& acc) const {
        if (started && inside && !led) endRun(tf, kEnd - kLast, s1, unit, acc);
    }

private:
    /// The segment from the last sample to one of value v lying at `at` over len, split at
    /// the isosurfaces it crosses (volume lit by vol). Not inlined: only frames with
    /// isosurfaces call it, and inlined it cost the shaded kernel its inlined add() (and with
    /// bisectIso, the 100M frames on the H100: PERFORMANCE.md, "Isosurfaces: what the surfaces'
    /// code costs a frame with no surface").
    UVR_HOST_DEVICE UVR_NOINLINE void withIsos(const TfTableView& tf, float v, float k, float s1,
                                               double unit, LightFactors vol, SamplePoint at,
                                               Vec4f& acc) {
        const double len = double(k - kLast) * s1;
        float f0 = 0.f, va = vLast;
        CrossingNormals normals;
        iso->crossings(vLast, v, [&](int i, float f) {
            if (acc.w >= segment::kOpacityEnd) return;
            const IsoSurface& s = iso->surfaces[i];
            integrateLit<kLit>(tf, va, s.value, double(f - f0) * len, unit, vol, acc);
            const RaySurfaces& r = *surfaces;
            const Vec3f gi = normals.at(*r.mesh, r.surface.smooth, atLast, at, f);
            const float a0 = acc.w;
            compositeIso(s, tf.sample(s.value).xyz(), lightFactors(r.surface, gi, r.dir), acc);
            const float depthAlpha = r.depthAlpha;
            if (depthAlpha > 0.f && !(kDepth < INFINITY) && a0 < depthAlpha && acc.w >= depthAlpha)
                kDepth = kLast + (k - kLast) * f;
            f0 = f, va = s.value;
        });
        if (acc.w >= segment::kOpacityEnd) return;
        integrateLit<kLit>(tf, va, v, double(1.f - f0) * len, unit, vol, acc);
    }

    /// The last sample's share: `steps` grid steps along the run's last slope (in double: the
    /// difference of two values may overflow float).
    UVR_HOST_DEVICE void endRun(const TfTableView& tf, float steps, float s1, double unit,
                                Vec4f& acc) const {
        double end = vLast;
        if (inRun) end += (double(vLast) - vPrev) * (double(steps) / (double(kLast) - kPrev));
        integrateLit<kLit>(tf, vLast, end, double(steps) * s1, unit, light, acc);
    }
};

/// The gradient at a sample in cell `tet` at local coordinates bary (TetMeshView::gradient,
/// smooth as the lighting asks) where the sample's light reads it (kLit, readsGradient); else,
/// or outside the mesh, 0. (The isosurfaces' normals are computed where they are crossed:
/// SamplePoint.)
template <bool kNative = true, bool kLit = true>
UVR_HOST_DEVICE inline Vec3f sampleGradient(const MarchParams& params, const TetMeshView& mesh,
                                            std::uint32_t tet, const float bary[4]) {
    if constexpr (kLit) {
        if (tet != kNoTet && readsGradient(params.light, params.gradientOpacity))
            return mesh.gradient<kNative>(tet, bary, params.light.smooth);
    }
    return Vec3f(0.f);
}

/// The light and gradient opacity of a sample of gradient g along a ray of unit direction dir:
/// the identity where an instance is compiled unlit (kLit false), when neither is on, or where
/// no cell holds the sample.
template <bool kLit = true>
UVR_HOST_DEVICE inline LightFactors lightAt(const Lighting& light, const GradientOpacity& gop,
                                            std::uint32_t tet, Vec3f g, Vec3f dir) {
    if constexpr (!kLit) {
        return {};
    } else {
        if (!readsGradient(light, gop) || tet == kNoTet) return {};
        return lightFactors(light, gop, g, dir);
    }
}

/// Point sampling with isosurfaces (kSurf): the surfaces crossed between consecutive samples
/// inside the mesh, where the value read linearly between them meets theirs, composited before
/// the later sample.
template <bool kSurf = true>
struct PointIsos {
    float vLast = 0.f;
    SamplePoint atLast;
    bool inside = false;

    /// The sample of value v lying at `at` in mesh (`in`: inside it).
    UVR_HOST_DEVICE void add(const MarchParams& params, const TetMeshView& mesh,
                             const TfTableView& tf, Vec3f dir, bool in, float v,
                             const SamplePoint& at, Vec4f& acc) {
        if constexpr (kSurf) {
            const IsoView& iso = params.iso;
            if (in && inside && iso.active()) {
                const Lighting surface = surfaceLighting(params.light);
                CrossingNormals normals;
                iso.crossings(vLast, v, [&](int i, float f) {
                    const IsoSurface& s = iso.surfaces[i];
                    const Vec3f gi = normals.at(mesh, surface.smooth, atLast, at, f);
                    compositeIso(s, tf.sample(s.value).xyz(), lightFactors(surface, gi, dir), acc);
                });
            }
            inside = in, vLast = v, atLast = at;
        }
    }
};

/// Bisection probes sampleAtBoundary takes for the mesh's boundary where its walk cannot follow
/// the ray: to within s1 / 2^10.
inline constexpr int kBoundaryBisections = 10;

/// A boundary within this many steps s1 of a run's end sample is at the sample: the run takes no
/// sample there. Without the margin, frames that differ only by rounding (a mesh moved or scaled,
/// a clip box around it) took a boundary sample in one and not the other where a face lies on a
/// grid position (a regular grid seen along an axis), and their pixels differed in the last bits
/// on the GPU.
inline constexpr float kBoundarySameSpot = 1e-3f;

/// Local coordinates that give a walk into a native cell no starting guess (TetLocator::walk
/// starts Newton's method from the coordinates it is given, when they lie near the cell): it
/// starts from the cell's centre, as a search does. Uninitialised coordinates made two renders
/// of one preparation differ in the last bits.
inline constexpr float kNoGuess = -9.f;

/// Runs call(counters, acc), a non-inlined surface call (sampleAtBoundary, bisectIso, cutFace),
/// on copies of a marcher's counters and colour, and takes them back. Given the marcher's own,
/// the call takes their addresses, so they live in local memory at every sample of the frame,
/// whether a surface is met or not (the reference's 100M isosurface frame: 5% faster on copies;
/// PERFORMANCE.md, "Isosurfaces: the surface calls on copies, and 255 registers").
template <class Call>
UVR_HOST_DEVICE UVR_INLINE void callOnCopies(RayCounters& counters, Vec4f& acc, const Call& call) {
    RayCounters c = counters;
    Vec4f a = acc;
    call(c, a);
    counters = c, acc = a;
}

/// callOnCopies with the marcher's segments too: call(segments, counters, acc).
template <bool kLit, bool kSurf, class Call>
UVR_HOST_DEVICE UVR_INLINE void callOnCopies(SampleSegments<kLit, kSurf>& segments,
                                             RayCounters& counters, Vec4f& acc, const Call& call) {
    SampleSegments<kLit, kSurf> s = segments;
    callOnCopies(counters, acc, [&](RayCounters& c, Vec4f& a) { call(s, c, a); });
    segments = s;
}

/// A run of samples (pre-integrated) starts and ends at the mesh's boundary (issue 29), not at
/// its first and last grid samples: between the sample at grid position kIn (inside, in cell
/// tetIn) and a position kOut outside the mesh or past the span's end (outKnown;
/// before kIn where a run starts, after it where one ends), or the start of the span (!outKnown,
/// before the first sample: the span may start inside the mesh, at a clip plane or the camera),
/// a walk from tetIn along the ray (backwards where a run starts) across shared faces finds the
/// face without a neighbour (boundaryAlong, exact to rounding; kOut itself where the ray is
/// still inside there); where the walk cannot follow the ray, probes by bisection, each located
/// by `locate(q, from, bary, counters)` from the last one found, narrow the boundary to within
/// s1 / 2^kBoundaryBisections. The run gets a sample at the boundary's inside end. A run that
/// starts there covers the distance from the boundary to
/// its first grid sample, a run that ends there stops at it (its last share ends there, so
/// kPieceEnd is read only where a run starts). Grid samples alone cover a run's n samples times
/// s1 from its first: a length off by up to s1 at each end, which drew rings on flat faces and
/// seams along silhouettes against exact (p99.9 11/255 on hexa.vtk and the Oxygen Post). A
/// surface between the boundary and the nearest grid sample (a thin layer at the mesh's skin,
/// which no pair of grid samples brackets) is crossed there as between any two samples. Not
/// inlined: it runs at a run's ends only (inlined with the other three surface calls, the 100M
/// isosurface frames got slower on the H100, and ptxas took twice as long).
template <bool kNative, bool kLit, bool kSurf, class Locate>
UVR_HOST_DEVICE UVR_NOINLINE void sampleAtBoundary(const Locate& locate, const MarchParams& params,
                                                   const TetLocator& loc, const TfTableView& tf,
                                                   const Ray& ray, const Lighting& lighting,
                                                   float kOut, bool outKnown, float kIn,
                                                   std::uint32_t tetIn, float kPieceEnd,
                                                   SampleSegments<kLit, kSurf>& segments,
                                                   RayCounters& counters, Vec4f& acc) {
    const float s1 = params.step;
    const bool entering = !outKnown || kOut < kIn;
    float hi = kIn;
    std::uint32_t tetHi = kNoTet;
    float baryHi[4] = {0.f, 0.f, 0.f, 0.f};
    // First cell to cell from the sample (backwards where a run starts), in double; a few cells
    // where they are about a step across.
    {
        const double tIn = double(kIn) * s1, tOut = double(kOut) * s1;
        const double eps = 1e-6 * fabs(tIn) + 1e-4 * s1;  // not of tOut: a clip box changes it
        std::uint32_t cell = tetIn;
        const Ray back{ray.org, Vec3f(-ray.dir.x, -ray.dir.y, -ray.dir.z)};
        const double tb = entering ? -boundaryAlong<kNative>(loc, cell, back, -tIn, -tOut, eps)
                                   : boundaryAlong<kNative>(loc, cell, ray, tIn, tOut, eps);
        if (tb == tb) {
            const float kb = static_cast<float>(tb / s1);
            if (entering ? kb >= kIn - kBoundarySameSpot : kb <= kIn + kBoundarySameSpot) {
                // At the sample: a run ending there ends at the sample.
                if (!entering && segments.kLast == kIn) segments.kEnd = kIn;
                return;
            }
            // Located a hair inside (the face itself may round to either side).
            const double nudge = (entering ? 1e-4 : -1e-4) * s1;
            float bary[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};
            ++counters.samples;
            const std::uint32_t t =
                locate(ray.at(static_cast<float>(tb + nudge)), cell, bary, counters.locate);
            if (t != kNoTet) {
                hi = kb, tetHi = t;
                for (int i = 0; i < 4; ++i) baryHi[i] = bary[i];
            }
        }
    }
    if (tetHi == kNoTet) {
        // Else by bisection: probes located from the last one found narrow the boundary to within
        // s1 / 2^kBoundaryBisections.
        float lo = kOut;
        std::uint32_t from = tetIn;
        float bary[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};
        if (!outKnown) {
            ++counters.samples;
            const std::uint32_t t = locate(ray.at(lo * s1), from, bary, counters.locate);
            if (t != kNoTet) {
                hi = lo, tetHi = t;
                for (int i = 0; i < 4; ++i) baryHi[i] = bary[i];
            }
        }
        for (int n = 0; n < kBoundaryBisections && hi != lo; ++n) {
            const float mid = 0.5f * (lo + hi);
            if (mid == lo || mid == hi) break;
            ++counters.samples;
            const std::uint32_t t = locate(ray.at(mid * s1), from, bary, counters.locate);
            if (t == kNoTet) {
                lo = mid;
            } else {
                hi = mid, from = tetHi = t;
                for (int i = 0; i < 4; ++i) baryHi[i] = bary[i];
            }
        }
    }
    if (tetHi == kNoTet || fabsf(hi - kIn) <= kBoundarySameSpot) {
        // The boundary lies within s1 / 2^kBoundaryBisections of the sample: a run ending there
        // ends at the sample.
        if (!entering && segments.kLast == kIn) segments.kEnd = kIn;
        return;
    }
    const float v = loc.mesh.interpolate<kNative>(tetHi, baryHi);
    const Vec3f g = sampleGradient<kNative, kLit>(params, loc.mesh, tetHi, baryHi);
    segments.add(tf, hi, entering ? kPieceEnd : hi, true, v, s1, params.opacityUnit, acc,
                 lightAt<kLit>(lighting, params.gradientOpacity, tetHi, g, ray.dir),
                 SamplePoint(tetHi, baryHi));
}

/// The clip region's cut face (ClipView::surface; kSurf instances): the point at parameter t of
/// the ray, on a face of normal n, located by `locate(q, hint, bary, counters)`; inside the mesh,
/// an opaque surface coloured by the transfer function at the field's value there, lit by the
/// headlight with normal n (`surface`: the frame's coefficients, always on), composited under what
/// acc holds and ending the ray. Returns whether the point lay inside the mesh. The depth asked for
/// (rayDepthAlpha) is reached there if not before.
template <bool kNative, class Locate>
UVR_HOST_DEVICE UVR_NOINLINE bool cutFace(const Locate& locate, const MarchParams& params,
                                          const TetMeshView& mesh, const TfTableView& tf,
                                          const Ray& ray, float t, Vec3f n, std::uint32_t hint,
                                          RayCounters& counters, Vec4f& acc) {
    float bary[4] = {kNoGuess, kNoGuess, kNoGuess, 0.f};
    ++counters.samples;
    const std::uint32_t c = locate(ray.at(t), hint, bary, counters.locate);
    if (c == kNoTet) return false;
    // An opaque surface coloured by the map (IsoSurface's defaults), composited as isosurfaces
    // are.
    compositeIso(IsoSurface{}, tf.sample(mesh.interpolate<kNative>(c, bary)).xyz(),
                 lightFactors(surfaceLighting(params.light), n, ray.dir), acc);
    if (rayDepthAlpha(params, counters) > 0.f && !(counters.depth < INFINITY)) counters.depth = t;
    return true;
}

/// The lighting an integrator instance reads: the frame's, or none where it is compiled unlit
/// and without surfaces (kLit and kSurf false: its kernels carry no lighting code, which cost the
/// unlit adaptive kernel up to 21% of its frame time on the H200). An unlit instance with
/// surfaces lights only them (surfaceLighting); its volume code is compiled out by kLit.
template <bool kLit, bool kSurf = false>
UVR_HOST_DEVICE inline Lighting kernelLighting(const MarchParams& params) {
    if constexpr (kLit || kSurf)
        return params.light;
    else
        return Lighting{};
}

/// The reference ray marcher: samples at fixed spacing s1 on the global grid t = k * s1 between
/// the ray's entry into and exit from the mesh bounds, locates each sample's tetrahedron
/// (previous tetrahedron first), interpolates barycentrically and integrates between
/// consecutive samples (SampleSegments; or, with params.preintegrated off, classifies each sample
/// through the transfer function and composites it with opacity correction), front to back,
/// stopping early once opaque: at `stop` (kSceneStop: at params.terminationAlpha).
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
UVR_HOST_DEVICE inline Vec4f marchReference(const SceneView& scene, const Ray& ray,
                                            RayCounters& counters, float stop = kSceneStop) {
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float t0 = 0.f, t1 = INFINITY;
    // An empty mesh has inverted bounds, which every ray would "cross" from -FLT_MAX to FLT_MAX.
    if (scene.bounds.empty() || !intersectBox(scene.bounds, ray.org, inv, t0, t1)) return acc;
    [[maybe_unused]] bool cut0 = false, cut1 = false;  // the span's ends on the clip's faces
    [[maybe_unused]] Vec3f n0, n1;
    const ClipView& clip = scene.params.clip;
    if (kSurf && clip.surface) {
        if (!clip.restrictFaces(ray.org, ray.dir, inv, t0, t1, cut0, n0, cut1, n1)) return acc;
    } else if (clip.active() && !clip.restrict(ray.org, ray.dir, inv, t0, t1)) {
        return acc;
    }
    if (ray.tMax < t1) t1 = ray.tMax, cut1 = false;  // depth in: opaque geometry there
    // A data-parallel frame: this rank's piece of the span (the cut faces at its ends are the
    // other ranks' where the piece moved them).
    bool pieceStart = false, pieceEnd = false;
    const float tSpan = t0;  // where one process's span starts
    if (!scene.params.piece.narrow(ray.org, inv, t0, t1, pieceStart, pieceEnd)) return acc;
    if (pieceStart) cut0 = false;
    if (pieceEnd) cut1 = false;
    if (!(t0 <= t1)) return acc;
    [[maybe_unused]] const auto locateAny = [&](Vec3f q, std::uint32_t from, float* b,
                                                LocateCounters& c) {
        return scene.locator.locate<kNative>(q, from, b, c);
    };
    if constexpr (kSurf) {  // the cut face in front: nothing else shows
        bool hit = false;
        if (cut0)
            callOnCopies(counters, acc, [&](RayCounters& c, Vec4f& a) {
                hit = cutFace<kNative>(locateAny, scene.params, scene.locator.mesh, scene.tf, ray,
                                       t0, n0, kNoTet, c, a);
            });
        if (hit) return acc;
    }
    const float s = scene.params.step;
    // Global sample grid k * s, so every integrator that samples a span takes the same samples.
    float k = ceilf(t0 / s);
    // The piece's last grid point lies before its end (the next piece takes the one on it);
    // past it the loop takes one more sample, kClose, which only ends the last segment.
    const float kEnd = pieceEnd ? ceilf(t1 / s) - 1.f : floorf(t1 / s);
    const float kClose = pieceEnd ? kEnd + 1.f : kEnd;
    std::uint32_t tet = kNoTet;
    float bary[4] = {0.f, 0.f, 0.f, 0.f};
    const float unit = scene.params.opacityUnit;
    const float stopAlpha = stop < 0.f ? scene.params.terminationAlpha : stop;
    SampleSegments<kLit, kSurf> segments;
    const Lighting lighting = kernelLighting<kLit, kSurf>(scene.params);
    const RaySurfaces surfaces(scene.params.iso, lighting, ray.dir,
                               rayDepthAlpha(scene.params, counters), scene.locator.mesh);
    segments.setIsos(surfaces);
    if (pieceStart && scene.params.preintegrated && k - 1.f >= ceilf(tSpan / s)) {
        // The piece before's last sample, in the ghost cells: the slope of the run the first
        // sample may continue, as one process's run has it.
        ++counters.samples;
        tet = scene.locator.locate<kNative>(ray.at((k - 1.f) * s), kNoTet, bary, counters.locate);
        segments.lead(k - 1.f, tet != kNoTet,
                      tet == kNoTet ? 0.f : scene.locator.mesh.interpolate<kNative>(tet, bary));
    }
    PointIsos<kSurf> pointIsos;
    std::uint32_t lastInside = kNoTet;  // the cell of the last sample inside
    // The loop leaves only through its condition, so GPU warps reconverge every iteration
    // (adaptive_marcher.h says why).
    bool opaque = false;
    [[maybe_unused]] float tNoted = t0;  // depth out: the end of the stretch of the ray noted last
    // Outside a non-convex mesh: the grid points below kOutside lie outside it, before the ray
    // enters it again (marchPartitions does the same; adaptive_marcher.h says why).
    float kOutside = -INFINITY;
    const double entryEps = cellGapEps(scene.bounds, t0);
    for (; k <= kClose && !opaque; k += 1.f) {
        const bool own = k <= kEnd;  // else the closing sample: its share is the next piece's
        [[maybe_unused]] const float a0 = acc.w;
        const Vec3f p = ray.at(k * s);
        ++counters.samples;
        if (k < kOutside) {
            tet = kNoTet;
        } else {
            tet = scene.locator.locate<kNative>(p, tet, bary, counters.locate);
            if (tet == kNoTet)
                kOutside = outsideUntil<kNative>(scene.locator.mesh, scene.locator.bvh, ray, k, s,
                                                 entryEps, counters.locate);
        }
        const float v = tet == kNoTet ? 0.f : scene.locator.mesh.interpolate<kNative>(tet, bary);
        const Vec3f g = sampleGradient<kNative, kLit>(scene.params, scene.locator.mesh, tet, bary);
        const LightFactors light =
            lightAt<kLit>(lighting, scene.params.gradientOpacity, tet, g, ray.dir);
        if (scene.params.preintegrated) {
            // A run starts and ends at the mesh's boundary (sampleAtBoundary). A data-parallel
            // piece's first sample after the piece before's last does not: that piece's closing
            // sample (kClose) found the boundary between them, as one process does.
            if ((tet != kNoTet) != segments.inside &&
                !(pieceStart && (!segments.started || segments.led))) {
                const bool first = !segments.started, in = tet != kNoTet;
                callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                    sampleAtBoundary<kNative, kLit, kSurf>(
                        locateAny, scene.params, scene.locator, scene.tf, ray, lighting,
                        in ? (first ? t0 / s : k - 1.f) : k, !first, in ? k : sc.kLast,
                        in ? tet : lastInside, kEnd + 1.f, sc, c, a);
                });
            }
            if (tet != kNoTet) lastInside = tet;
            segments.add(scene.tf, k, kEnd + 1.f, tet != kNoTet, v, s, unit, acc, light,
                         SamplePoint(tet, bary));
        } else {
            pointIsos.add(scene.params, scene.locator.mesh, scene.tf, ray.dir, tet != kNoTet, v,
                          SamplePoint(tet, bary), acc);
        }
        if (!scene.params.preintegrated && tet != kNoTet && own) {
            const Vec4f c = scene.tf.sample(v);
            const float a = correctOpacity(c.w, s * light.opacity, unit, scene.tf.law);
            if (a > 0.f) compositeFrontToBack(acc, light.apply(c.xyz()), a);
        }
        if constexpr (kSurf) {
            if (segments.kDepth < INFINITY && !(counters.depth < INFINITY))
                counters.depth = segments.kDepth * s;
            noteDepth(rayDepthAlpha(scene.params, counters), a0, acc.w, tNoted, k * s, counters);
            tNoted = k * s;
        }
        opaque = acc.w >= stopAlpha;
        // Outside, before the ray's next entry: on to the last grid point before it (at most
        // the closing sample), so the step into the mesh is one s as before.
        if (tet == kNoTet && k + 2.f < kOutside) {
            const float last = fminf(lastOutside(k, kOutside), kClose);
            if (last > k + 1.f) k = last - 1.f;
        }
    }
    if (scene.params.preintegrated && !opaque && !pieceEnd) {
        [[maybe_unused]] const float a0 = acc.w;
        // A run reaching the span's end (the mesh's boundary, the bounds' face, a clip plane,
        // depth in) ends at the boundary or the end, whichever comes first.
        if (segments.inside) {
            callOnCopies(segments, counters, acc, [&](auto& sc, RayCounters& c, Vec4f& a) {
                sampleAtBoundary<kNative, kLit, kSurf>(locateAny, scene.params, scene.locator,
                                                       scene.tf, ray, lighting, t1 / s, true,
                                                       sc.kLast, lastInside, kEnd + 1.f, sc, c, a);
            });
        }
        segments.finish(scene.tf, s, unit, acc);
        if constexpr (kSurf)
            noteDepth(rayDepthAlpha(scene.params, counters), a0, acc.w, tNoted, t1, counters);
    }
    if constexpr (kSurf) {  // the cut face behind the volume
        if (cut1 && !opaque)
            callOnCopies(counters, acc, [&](RayCounters& c, Vec4f& a) {
                cutFace<kNative>(locateAny, scene.params, scene.locator.mesh, scene.tf, ray, t1, n1,
                                 tet, c, a);
            });
    }
    return acc;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

// The exact integrator (issue 11): each ray walks tetrahedron to tetrahedron across faces and
// integrates the emission-absorption model over every tetrahedron's segment without sampling.
//
// The model is the limit the sample-based methods converge to as their step goes to 0
// (segment_integral.h): inside a linear tetrahedron the scalar is linear along the ray, so each
// tetrahedron's segment is integrated in closed form, split only at the transfer function's
// breakpoints (pieces in float, segment::compositePieceFast: within 1e-4 of the double form).
// Rays that leave a non-convex mesh, cross a seam of unshared faces or meet a degenerate crossing
// (an edge or vertex) are located again through the mesh BVH from where they are: nothing along
// the ray is dropped.

#include <cmath>
#include <cstdint>

#include "uvr/accel/bvh.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/vec3d.h"
#include "uvr/render/ray_cells.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/render/segment_integral.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Most tetrahedra one ray of the exact integrator visits (a guard against endless walks; a ray
/// through a billion-tetrahedron mesh crosses a few thousand).
inline constexpr std::uint32_t kExactMaxSteps = 1u << 22;

namespace exact {

/// Most pieces smoothLitSegment cuts a segment into, and the change of light (scale plus add,
/// plus the gradient opacity's) a piece may span.
inline constexpr int kLightMaxPieces = 8;
inline constexpr float kLightPieceChange = 0.01f;

/// Pieces a lit segment needs from the lights at its start a, middle c and end b: about one per
/// kLightPieceChange of change between the ends or of bend in the middle (four times its
/// distance from the ends' mean), at most kLightMaxPieces.
UVR_HOST_DEVICE inline int lightPieces(const LightFactors& a, const LightFactors& c,
                                       const LightFactors& b) {
    const float ends =
        fabsf(b.scale - a.scale) + fabsf(b.add - a.add) + fabsf(b.opacity - a.opacity);
    const float bend =
        4.f * (fabsf(c.scale - 0.5f * (a.scale + b.scale)) + fabsf(c.add - 0.5f * (a.add + b.add)) +
               fabsf(c.opacity - 0.5f * (a.opacity + b.opacity)));
    const float want = ceilf((ends > bend ? ends : bend) / kLightPieceChange);
    return want <= 1.f ? 1 : (want < kLightMaxPieces ? int(want) : kLightMaxPieces);
}

/// Simpson's weights over the lights at a segment's start, middle and end.
UVR_HOST_DEVICE inline LightFactors simpsonLight(const LightFactors& a, const LightFactors& c,
                                                 const LightFactors& b) {
    return {(a.scale + 4.f * c.scale + b.scale) * (1.f / 6.f),
            (a.add + 4.f * c.add + b.add) * (1.f / 6.f),
            (a.opacity + 4.f * c.opacity + b.opacity) * (1.f / 6.f)};
}

/// Most pieces a native cell's segment is cut into (nativeSegment).
inline constexpr int kNativeMaxPieces = 16;
/// Evaluations of a native cell's field that place an isosurface's crossing (nativeSegment).
inline constexpr int kIsoRefinements = 4;

/// The point field along the ray through native cell t from t0 to t1 (issue 14): the inverse
/// isoparametric map is not closed-form along a ray (a trilinear field is a cubic in t only in a
/// parallelepiped), so the segment is cut into n equal pieces over which the field is taken as
/// linear, each piece's end values from Newton's method (each start from the last point's
/// coordinates). n follows the deviation d of the midpoint's value from the mean of the ends:
/// a piece's deviation falls as 1 / n^2, so n = ceil(sqrt(d / tol)) with tol a quarter of a
/// table entry's value width, at most kNativeMaxPieces. `v0` is the value at t0 (the previous
/// cell's exit value, or NaN: computed here); returns the value at t1. Composites into acc; lit
/// (gradient shading), each piece by the mean of its ends' lights (the gradient through the
/// cell's Jacobian at the Newton iterate's coordinates), and scaled likewise by the gradient
/// opacity `gop`. With isosurfaces (iso, kSurf), a piece
/// crossing one is cut where the cell's own field meets its value (regula falsi from the
/// piece's linear reading, kIsoRefinements evaluations) and the surface composited there.
template <bool kLit = true, bool kSurf = kLit>
UVR_HOST_DEVICE inline float nativeSegment(const TetMeshView& mesh, const TfTableView& tf,
                                           std::uint32_t t, const Ray& ray, double t0, double t1,
                                           float v0, double unit, const Lighting& light,
                                           const GradientOpacity& gop, Vec4f& acc,
                                           const IsoView* iso = nullptr) {
    Vec3f x[kMaxCellCorners];
    float cv[kMaxCellCorners];
    const int n = mesh.gather(t, x, cv);
    const CellKind k = mesh.kind(t);
    // The shape functions are a convex combination: the value lies within the corners' (as
    // TetSpan::valueAt's). Unclamped, float rounding put it an ulp above the range's top on a
    // wall at the field's maximum: a real sliver past the table's last entry, which under the
    // transmittance law at opacity 1 made the ray opaque (speckle on disk_out_ref.ex2).
    float cvLo = cv[0], cvHi = cv[0];
    for (int i = 1; i < n; ++i) {
        cvLo = cv[i] < cvLo ? cv[i] : cvLo;
        cvHi = cv[i] > cvHi ? cv[i] : cvHi;
    }
    Vec3f rst = cellCentreParametric(k);
    auto valueAt = [&](double tp) {
        const Vec3f p = ray.at(static_cast<float>(tp));
        cellParametric(k, x, p, rst, true);
        const Vec3f c = clampParametric(k, rst);
        float w[kMaxCellCorners];
        shapeFunctions(k, c.x, c.y, c.z, w);
        float v = 0.f;
        for (int i = 0; i < n; ++i) v += w[i] * cv[i];
        return v < cvLo ? cvLo : (v > cvHi ? cvHi : v);  // NaN stays NaN
    };
    // The light at the parametric coordinates rst of the last point valueAt took (the
    // volume's only where the instance is lit; the isosurfaces' always).
    auto lightWith = [&](const Lighting& l, const GradientOpacity& g) {
        if (!readsGradient(l, g)) return LightFactors{};
        const float at[4] = {rst.x, rst.y, rst.z, 0.f};
        return lightFactors(l, g, mesh.gradient(t, at, l.smooth), ray.dir);
    };
    auto lightHere = [&]() { return kLit ? lightWith(light, gop) : LightFactors{}; };
    const float vMid = valueAt(0.5 * (t0 + t1));
    const Vec3f rstMid = rst;
    LightFactors lightA;  // at the start of the piece
    if (!(v0 == v0)) {
        v0 = valueAt(t0);
        lightA = lightHere();
    } else if (kLit && readsGradient(light, gop)) {
        (void)valueAt(t0);  // for its coordinates only
        lightA = lightHere();
        rst = rstMid;  // t1's Newton starts where it would unlit
    }
    const float vEnd = valueAt(t1);
    const LightFactors lightEnd = lightHere();
    const double tol = 0.25 * (double(tf.hi) - tf.lo) / (tf.count > 1 ? tf.count - 1 : 1);
    const double dev = fabs(double(vMid) - 0.5 * (double(v0) + vEnd));
    int pieces = 1;
    if (dev > tol || !(tol > 0.0)) {
        const double want = tol > 0.0 ? ceil(sqrt(dev / tol)) : double(kNativeMaxPieces);
        pieces = want < kNativeMaxPieces ? (want > 2.0 ? int(want) : 2) : kNativeMaxPieces;
    }
    // Lit: also as many pieces as the light's change asks (the gradient turns in the cell).
    LightFactors lightMid;
    if (kLit && readsGradient(light, gop)) {
        const Vec3f at = rst;
        rst = rstMid;
        lightMid = lightHere();
        rst = at;
        const int lit = lightPieces(lightA, lightMid, lightEnd);
        pieces = lit > pieces ? lit : pieces;
    }
    if (pieces == 1 && !(kSurf && iso)) {
        integrateLit<kLit>(tf, v0, vEnd, t1 - t0, unit, simpsonLight(lightA, lightMid, lightEnd),
                           acc);
        return vEnd;
    }
    rst = rstMid;  // a good start for the pieces' points in the middle; each follows the last
    float a = v0;
    const double h = (t1 - t0) / pieces;
    for (int i = 1; i <= pieces && acc.w < segment::kOpacityEnd; ++i) {
        const float b = i == pieces ? vEnd : valueAt(t0 + h * i);
        const LightFactors lightB = i == pieces ? lightEnd : lightHere();
        const LightFactors vol = lightA.mean(lightB);
        double ta = t0 + h * (i - 1), len = h;  // the rest of the piece: from ta, len long
        float va = a;
        if constexpr (kSurf) {
            if (iso) {
                const double tb = i == pieces ? t1 : t0 + h * i;
                const Lighting surface = surfaceLighting(light);
                iso->crossings(a, b, [&](int j, float f) {
                    if (acc.w >= segment::kOpacityEnd) return;
                    const float c = iso->surfaces[j].value;
                    // Regula falsi on the cell's field over [lo, hi], from the linear guess.
                    double lo = ta, hi = tb, tc = ta + (tb - ta) * f;
                    float flo = va - c, fhi = b - c;
                    for (int r = 0; r < kIsoRefinements && flo != fhi; ++r) {
                        tc = lo + (hi - lo) * (double(flo) / (double(flo) - fhi));
                        const float fc = valueAt(tc) - c;
                        if (fc == 0.f || !(fc == fc)) break;
                        ((fc < 0.f) == (flo < 0.f) ? lo : hi) = tc;
                        ((fc < 0.f) == (flo < 0.f) ? flo : fhi) = fc;
                    }
                    integrateLit<kLit>(tf, va, c, tc - ta, unit, vol, acc);
                    (void)valueAt(tc);  // the surface's coordinates, for its normal
                    compositeIso(iso->surfaces[j], tf.sample(c).xyz(),
                                 lightWith(surface, GradientOpacity{}), acc);
                    ta = tc, va = c, len = tb - tc;
                });
            }
        }
        if (acc.w < segment::kOpacityEnd) integrateLit<kLit>(tf, va, b, len, unit, vol, acc);
        a = b;
        lightA = lightB;
    }
    return vEnd;
}

/// The light (and gradient opacity gop) at parameter t of the ray inside tetrahedron tet:
/// smooth, its corners' gradients at the point's barycentrics (clamped to the cell); per cell,
/// its constant gradient.
template <bool kNative = true>
UVR_HOST_DEVICE inline LightFactors lightInTet(const TetMeshView& m, std::uint32_t tet,
                                               const Ray& ray, double t, const Lighting& light,
                                               const GradientOpacity& gop = GradientOpacity{}) {
    float bary[4] = {0.25f, 0.25f, 0.25f, 0.25f};
    if (light.smooth && m.blockGradients) {
        BlockVertex x[4];
        m.tetVertices(tet, x);
        float b[4];
        if (tetBarycentrics(ray.at(static_cast<float>(t)), x[0].p, x[1].p, x[2].p, x[3].p, b)) {
            float sum = 0.f;
            for (float& v : b) v = v > 0.f ? v : 0.f, sum += v;
            if (sum > 0.f)
                for (int i = 0; i < 4; ++i) bary[i] = b[i] / sum;
        }
    }
    return lightFactors(light, gop, m.gradient<kNative>(tet, bary, light.smooth), ray.dir);
}

/// A tetrahedron's segment [t0, t1] (scalar linear from v0 to v1) lit by smooth normals, into
/// acc: the interpolated gradient turns along it, so the light is not constant. From the lights
/// at its ends and middle, the segment is cut into n equal pieces (at most kLightMaxPieces) so
/// that each spans a change of light of about kLightPieceChange; each piece is lit by the mean
/// of its ends' lights (one piece: Simpson's weights over ends and middle).
template <bool kNative = true>
UVR_HOST_DEVICE inline void smoothLitSegment(const TetMeshView& m, const TfTableView& tf,
                                             std::uint32_t tet, const Ray& ray, double t0,
                                             double t1, float v0, float v1, double unit,
                                             const Lighting& light, const GradientOpacity& gop,
                                             Vec4f& acc) {
    const LightFactors a = lightInTet<kNative>(m, tet, ray, t0, light, gop);
    const LightFactors b = lightInTet<kNative>(m, tet, ray, t1, light, gop);
    const LightFactors c = lightInTet<kNative>(m, tet, ray, 0.5 * (t0 + t1), light, gop);
    const int n = lightPieces(a, c, b);
    if (n == 1) {
        integrateLit(tf, v0, v1, t1 - t0, unit, simpsonLight(a, c, b), acc);
        return;
    }
    LightFactors la = a;
    float va = v0;
    const double h = (t1 - t0) / n;
    for (int i = 1; i <= n && acc.w < segment::kOpacityEnd; ++i) {
        const float vb = i == n ? v1 : v0 + (v1 - v0) * (float(i) / float(n));
        const LightFactors lb =
            i == n ? b : lightInTet<kNative>(m, tet, ray, t0 + h * i, light, gop);
        integrateLit(tf, va, vb, h, unit, la.mean(lb), acc);
        va = vb;
        la = lb;
    }
}

/// Scalar at parameter t of the ray inside tetrahedron tet: from the span's linear function
/// when it has one, else barycentric at the point (clamped to the cell).
template <bool kNative = true>
UVR_HOST_DEVICE inline float scalarAt(const TetLocator& loc, std::uint32_t tet, const TetSpan& span,
                                      const Ray& ray, double t) {
    const TetMeshView& m = loc.mesh;
    if (m.cellCentered) return m.values[tet];
    if (span.hasValue) return span.valueAt(t);
    BlockVertex x[4];
    m.tetVertices(tet, x);
    float bary[4];
    const Vec3f p = ray.at(static_cast<float>(t));
    if (!tetBarycentrics(p, x[0].p, x[1].p, x[2].p, x[3].p, bary))
        for (float& b : bary) b = 0.25f;  // a degenerate tetrahedron: the mean of its corners
    float sum = 0.f;
    for (float& b : bary) b = b > 0.f ? b : 0.f, sum += b;
    if (sum > 0.f)
        for (float& b : bary) b /= sum;
    return m.interpolate<kNative>(tet, bary);
}

/// The piece [ta, tb] of tetrahedron tet's segment, the scalar linear from va to vb, into acc:
/// float pieces (within 1e-4 of the double closed form, deep pieces in double), lit (kLit) per
/// cell (a tetrahedron's gradient is constant, so is its light along the segment) or by smooth
/// normals (smoothLitSegment), and the ray's depth noted (kSurf).
template <bool kNative, bool kLit, bool kSurf>
UVR_HOST_DEVICE UVR_INLINE void tetPiece(const SceneView& scene, std::uint32_t tet, const Ray& ray,
                                         double ta, double tb, float va, float vb,
                                         const Lighting& light, bool continuous,
                                         RayCounters& counters, Vec4f& acc) {
    const TetMeshView& mesh = scene.locator.mesh;
    const double unit = scene.params.opacityUnit;
    if constexpr (kLit) {
        if (readsGradient(light, scene.params.gradientOpacity) && light.smooth &&
            mesh.blockGradients && continuous) {
            const float a0 = acc.w;
            smoothLitSegment<kNative>(mesh, scene.tf, tet, ray, ta, tb, va, vb, unit, light,
                                      scene.params.gradientOpacity, acc);
            if constexpr (kSurf)
                noteDepth(rayDepthAlpha(scene.params, counters), a0, acc.w, float(ta), float(tb),
                          counters);
            return;
        }
    }
    [[maybe_unused]] const float a0 = acc.w;
    LightFactors f;
    if constexpr (kLit)
        if (readsGradient(light, scene.params.gradientOpacity))
            f = lightInTet<kNative>(mesh, tet, ray, tb, light, scene.params.gradientOpacity);
    integrateLit<kLit>(scene.tf, va, vb, tb - ta, unit, f, acc);
    if constexpr (kSurf)
        noteDepth(rayDepthAlpha(scene.params, counters), a0, acc.w, float(ta), float(tb), counters);
}

/// A tetrahedron's segment [t, tEnd] (scalar linear from s0 to s1) with the frame's
/// isosurfaces: integrated up to each crossing (exact: the scalar is linear), the surface
/// composited there, lit by its normal at that point, and the rest after it. Not inlined: only
/// frames with isosurfaces call it. The volume is lit where the instance is (kLit); the
/// surfaces always are.
template <bool kNative, bool kLit>
UVR_HOST_DEVICE UVR_NOINLINE void isoTetSegment(const SceneView& scene, std::uint32_t tet,
                                                const Ray& ray, double t, double tEnd, float s0,
                                                float s1, const Lighting& light,
                                                RayCounters& counters, Vec4f& acc) {
    const IsoView& isos = scene.params.iso;
    double ta = t;
    float va = s0;
    isos.crossings(s0, s1, [&](int i, float f) {
        if (acc.w >= segment::kOpacityEnd) return;
        const IsoSurface& iso = isos.surfaces[i];
        const double tc = t + (tEnd - t) * double(f);
        tetPiece<kNative, kLit, true>(scene, tet, ray, ta, tc, va, iso.value, light, true, counters,
                                      acc);
        const LightFactors lit =
            lightInTet<kNative>(scene.locator.mesh, tet, ray, tc, surfaceLighting(light));
        const float a0 = acc.w;
        compositeIso(iso, scene.tf.sample(iso.value).xyz(), lit, acc);
        noteDepth(rayDepthAlpha(scene.params, counters), a0, acc.w, float(tc), float(tc), counters);
        ta = tc, va = iso.value;
    });
    if (acc.w < segment::kOpacityEnd)
        tetPiece<kNative, kLit, true>(scene, tet, ray, ta, tEnd, va, s1, light, true, counters,
                                      acc);
}

}  // namespace exact

/// The exact integrator for one ray (see the top of this file).
template <bool kNative = true, bool kLit = true, bool kSurf = kLit>
UVR_HOST_DEVICE inline Vec4f integrateExact(const SceneView& scene, const Ray& ray,
                                            RayCounters& counters) {
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    if (scene.bounds.empty()) return acc;
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float b0 = 0.f, b1 = INFINITY;
    if (!intersectBox(scene.bounds, ray.org, inv, b0, b1)) return acc;
    // Clipped: the ray starts at the region's entry (inside a cell, which is cut there) and
    // stops at its exit.
    const ClipView& clip = scene.params.clip;
    [[maybe_unused]] bool cut0 = false, cut1 = false;  // the span's ends on the clip's faces
    [[maybe_unused]] Vec3f n0, n1;
    if (kSurf && clip.surface) {
        if (!clip.restrictFaces(ray.org, ray.dir, inv, b0, b1, cut0, n0, cut1, n1)) return acc;
    } else if (clip.active() && !clip.restrict(ray.org, ray.dir, inv, b0, b1)) {
        return acc;
    }
    // Depth in: the ray ends at opaque geometry (cut there as at a clip plane).
    if (ray.tMax < b1) b1 = ray.tMax, cut1 = false;
    // A data-parallel frame: this rank's piece of the span, its cells cut at the piece's box as
    // at a clip plane (the cut faces at its ends are the other ranks' where it moved them).
    bool pieceStart = false, pieceEnd = false;
    if (!scene.params.piece.narrow(ray.org, inv, b0, b1, pieceStart, pieceEnd)) return acc;
    if (pieceStart) cut0 = false;
    if (pieceEnd) cut1 = false;
    if (!(b0 <= b1)) return acc;
    [[maybe_unused]] const auto locateAny = [&](Vec3f q, std::uint32_t from, float* b,
                                                LocateCounters& c) {
        return scene.locator.locate<kNative>(q, from, b, c);
    };
    if constexpr (kSurf) {  // the cut face in front: nothing else shows
        if (cut0 && cutFace<kNative>(locateAny, scene.params, scene.locator.mesh, scene.tf, ray, b0,
                                     n0, kNoTet, counters, acc))
            return acc;
    }
    const bool clipped = clip.active() || ray.tMax < INFINITY || scene.params.piece.active;
    const double tStop = clipped ? double(b1) : INFINITY;
    const TetLocator& loc = scene.locator;
    // A gap this small between tetrahedra is rounding, not empty space.
    const double eps = cellGapEps(scene.bounds, b0);
    const double unit = scene.params.opacityUnit;
    const Lighting lighting = kernelLighting<kLit, kSurf>(scene.params);
    const IsoView* isos = kSurf && scene.params.iso.active() ? &scene.params.iso : nullptr;
    double t = b0;
    exact::TetSpan span;
    std::uint32_t tet =
        exact::nextTetAlong<kNative>(loc.mesh, loc.bvh, ray, t, eps, span, counters.locate);
    const bool continuous = !loc.mesh.cellCentered;
    if (tet != kNoTet) {
        if (continuous)
            span = exact::clipAny<kNative>(loc.mesh, tet, ray, true, t + eps);  // with the field
        if (span.tIn > t) t = span.tIn;  // empty space before the mesh
    }
    // The loop leaves only through its condition, so GPU warps reconverge every iteration
    // (adaptive_marcher.h says why).
    bool opaque = false;
    bool past = clipped && tet != kNoTet && t >= tStop;  // beyond the clip region's exit
    // A point field is continuous across a shared face: the value where the ray leaves one
    // tetrahedron is where it enters the next (when it continues through that face).
    bool haveEntry = false;
    float sEntry = 0.f;
    for (std::uint32_t step = 0; tet != kNoTet && !opaque && !past && step < kExactMaxSteps;
         ++step) {
        // Unclipped, the cell's exit as it is (NaN for a degenerate crossing: nothing then).
        const double tEnd = clipped && span.tOut > tStop ? tStop : span.tOut;
        bool exitValue = false;
        if (tEnd > t) {
            ++counters.samples;  // one segment per cell crossed
            float s1;
            [[maybe_unused]] const float depthAlpha = rayDepthAlpha(scene.params, counters);
            if (kNative && continuous && tet >= loc.mesh.tetCount) {
                [[maybe_unused]] const float a0 = acc.w;
                s1 = exact::nativeSegment<kLit, kSurf>(loc.mesh, scene.tf, tet, ray, t, tEnd,
                                                       haveEntry ? sEntry : NAN, unit, lighting,
                                                       scene.params.gradientOpacity, acc, isos);
                if constexpr (kSurf) noteDepth(depthAlpha, a0, acc.w, t, tEnd, counters);
            } else {
                const float s0 =
                    haveEntry ? sEntry : exact::scalarAt<kNative>(loc, tet, span, ray, t);
                s1 = exact::scalarAt<kNative>(loc, tet, span, ray, tEnd);
                // Isosurfaces: the segment is cut where its linear scalar meets them (a call
                // of its own: frames without them keep the inlined piece alone).
                bool done = false;
                if constexpr (kSurf) {
                    if (isos && continuous) {
                        exact::isoTetSegment<kNative, kLit>(scene, tet, ray, t, tEnd, s0, s1,
                                                            lighting, counters, acc);
                        done = true;
                    }
                }
                if (!done)
                    exact::tetPiece<kNative, kLit, kSurf>(scene, tet, ray, t, tEnd, s0, s1,
                                                          lighting, continuous, counters, acc);
            }
            opaque = acc.w >= segment::kOpacityEnd;
            past = clipped && tEnd >= tStop;
            if (opaque || past) continue;
            t = tEnd;
            sEntry = s1;
            // A NaN tetrahedron's exit value is not the next one's entry value (that one's
            // field is its own, finite where its vertices are).
            exitValue = continuous && s1 == s1;
        }
        haveEntry = false;
        // Across the exit face; located again where there is no neighbour or the crossing is
        // degenerate (the neighbour's span does not continue the ray).
        const std::uint32_t next = loc.neighbors.present() && span.exitFace >= 0
                                       ? loc.neighbors.across<kNative>(loc.mesh, tet, span.exitFace)
                                       : kNoTet;
        if (next != kNoTet) {
            const exact::TetSpan s =
                exact::clipAny<kNative>(loc.mesh, next, ray, continuous, t + eps);
            if (s.tOut > t + eps && s.tIn <= t + eps) {
                tet = next;
                span = s;
                haveEntry = exitValue;
                continue;
            }
        }
        tet = exact::nextTetAlong<kNative>(loc.mesh, loc.bvh, ray, t, eps, span, counters.locate);
        if (tet != kNoTet) {
            if (continuous) span = exact::clipAny<kNative>(loc.mesh, tet, ray, true, t + eps);
            if (span.tIn > t) t = span.tIn;  // empty space before it
            past = clipped && t >= tStop;
        }
    }
    if constexpr (kSurf) {  // the cut face behind the volume
        if (cut1 && !opaque)
            cutFace<kNative>(locateAny, scene.params, scene.locator.mesh, scene.tf, ray, b1, n1,
                             kNoTet, counters, acc);
    }
    return acc;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

// The exact integrator (issue 11): each ray walks tetrahedron to tetrahedron across faces and
// integrates the emission-absorption model over every tetrahedron's segment without sampling.
//
// The model is the limit the sample-based methods converge to as their step goes to 0: a
// transfer-function opacity alpha per opacity unit u is the extinction kappa(s) = -ln(1 - alpha(s))
// / u (the marchers' opacity correction 1 - (1 - alpha)^(step / u) is exactly exp(-kappa step)),
// and the emission is c(s) kappa(s). The transfer function is the baked table, linear between its
// entries; inside a linear tetrahedron the scalar is linear along the ray. So a segment splits at
// the table entries it crosses into pieces where colour and opacity are linear in the distance t:
// - the optical depth of a piece is closed-form: with w(t) = 1 - alpha(t) linear,
//   integral of -ln w dt = t * (-(F(w) - F(w0)) / (w - w0)), F(w) = w ln w - w;
// - the colour is integrated by parts, c kappa T = -c dT/dt with c linear: c0 - c1 T(L) + c' *
//   integral of T, and the mean transmittance of the piece by composite Gauss-Legendre quadrature
//   of the closed-form T (smooth and monotone), to about 1e-9.
// Rays that leave a non-convex mesh, cross a seam of unshared faces or meet a degenerate crossing
// (an edge or vertex) are located again through the mesh BVH from where they are: nothing along
// the ray is dropped.

#include <cmath>
#include <cstdint>

#include "uvr/accel/bvh.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/vec3d.h"
#include "uvr/render/reference_marcher.h"
#include "uvr/tf/tf_table.h"

namespace uvr {

/// Accumulated opacity at which the exact integrator stops (what is left changes a pixel by less
/// than 1e-6).
inline constexpr float kExactOpacityEnd = 0.999999f;

/// Most tetrahedra one ray of the exact integrator visits (a guard against endless walks; a ray
/// through a billion-tetrahedron mesh crosses a few thousand).
inline constexpr std::uint32_t kExactMaxSteps = 1u << 22;

namespace exact {

/// (F(w1) - F(w0)) / (w1 - w0) for F(w) = w ln w - w: the mean of ln w over [w0, w1] (w >= 0).
UVR_HOST_DEVICE inline double meanLog(double w0, double w1) {
    const double d = w1 - w0;
    if (fabs(d) <= 1e-7 * fmax(w0, w1)) return log(0.5 * (w0 + w1));
    auto F = [](double w) { return w > 0.0 ? w * log(w) - w : 0.0; };
    return (F(w1) - F(w0)) / d;
}

/// Optical depth from 0 to t of a piece of length len whose opacity runs linearly from a0 to a1
/// (both below 1 or one of them 1), per opacity unit `unit`.
UVR_HOST_DEVICE inline double opticalDepth(double a0, double a1, double len, double t,
                                           double unit) {
    if (t <= 0.0) return 0.0;
    const double w0 = 1.0 - a0;
    const double wt = 1.0 - (a0 + (a1 - a0) * (t / len));
    return -t * meanLog(w0, wt > 0.0 ? wt : 0.0) / unit;
}

/// Mean transmittance (1 / len) * integral of exp(-tau(t)) over a piece of constant extinction
/// and optical depth tau.
UVR_HOST_DEVICE inline double meanTransmittanceConstant(double tau) {
    return tau > 1e-12 ? -expm1(-tau) / tau : 1.0 - 0.5 * tau;
}

/// Mean transmittance over a piece whose opacity runs linearly from a0 to a1 (optical depth
/// tauEnd in all): beyond optical depth 40 nothing is left, so 4-point Gauss-Legendre quadrature
/// spans [0, tStop] with about one sub-interval per 0.25 of optical depth.
UVR_HOST_DEVICE inline double meanTransmittance(double a0, double a1, double len, double unit,
                                                double tauEnd) {
    double tStop = len;
    if (tauEnd > 40.0) {
        double lo = 0.0, hi = len;  // tau is increasing: bisect tau(t) = 40
        for (int i = 0; i < 60; ++i) {
            const double mid = 0.5 * (lo + hi);
            (opticalDepth(a0, a1, len, mid, unit) < 40.0 ? lo : hi) = mid;
        }
        tStop = hi;
    }
    const double tauStop = tauEnd > 40.0 ? 40.0 : tauEnd;
    int parts = static_cast<int>(tauStop / 0.25) + 1;
    parts = parts < 256 ? parts : 256;
    // 4-point Gauss-Legendre nodes and weights on [-1, 1].
    const double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                         0.8611363115940526};
    const double wgt[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                           0.3478548451374538};
    const double h = tStop / parts;
    double integral = 0.0;
    for (int p = 0; p < parts; ++p) {
        const double mid = (p + 0.5) * h;
        for (int k = 0; k < 4; ++k)
            integral +=
                wgt[k] * 0.5 * h * exp(-opticalDepth(a0, a1, len, mid + 0.5 * h * x[k], unit));
    }
    return integral / len;
}

/// Composites a piece of length len, colour and opacity linear from c0, a0 to c1, a1, into the
/// premultiplied accumulator (front to back).
UVR_HOST_DEVICE inline void compositePiece(Vec3f c0, double a0, Vec3f c1, double a1, double len,
                                           double unit, Vec4f& acc) {
    if (!(len > 0.0)) return;
    a0 = a0 > 0.0 ? (a0 < 1.0 ? a0 : 1.0) : 0.0;
    a1 = a1 > 0.0 ? (a1 < 1.0 ? a1 : 1.0) : 0.0;
    if (a0 == 0.0 && a1 == 0.0) return;
    const double remaining = 1.0 - acc.w;
    if (a0 >= 1.0 && a1 >= 1.0) {  // infinite extinction: opaque at once
        acc.x += static_cast<float>(remaining * c0.x);
        acc.y += static_cast<float>(remaining * c0.y);
        acc.z += static_cast<float>(remaining * c0.z);
        acc.w = 1.f;
        return;
    }
    const double tauEnd = opticalDepth(a0, a1, len, len, unit);
    const double transEnd = exp(-tauEnd);
    const double mean =
        a0 == a1 ? meanTransmittanceConstant(tauEnd) : meanTransmittance(a0, a1, len, unit, tauEnd);
    // Colour by parts: c0 (1 - M) + c1 (M - T(len)).
    const double k0 = remaining * (1.0 - mean), k1 = remaining * (mean - transEnd);
    acc.x += static_cast<float>(k0 * c0.x + k1 * c1.x);
    acc.y += static_cast<float>(k0 * c0.y + k1 * c1.y);
    acc.z += static_cast<float>(k0 * c0.z + k1 * c1.z);
    acc.w = static_cast<float>(1.0 - remaining * transEnd);
}

/// Table entry value (RGBA) at a position g in [0, count - 1] of the table, linear between
/// entries.
UVR_HOST_DEVICE inline Vec4f tableAt(const TfTableView& tf, double g) {
    const int last = tf.count - 1;
    if (!(g > 0.0)) return tf.entries[0];
    if (g >= last) return tf.entries[last];
    const int i = static_cast<int>(g);
    const float w = static_cast<float>(g - i);
    return tf.entries[i] * (1.f - w) + tf.entries[i + 1] * w;
}

/// Integrates a segment of length len along which the scalar runs linearly from s0 to s1
/// through the transfer function, split at the table entries it crosses, into acc. A NaN end
/// makes the segment transparent (as a NaN sample is).
UVR_HOST_DEVICE inline void integrateSegment(const TfTableView& tf, float s0, float s1, double len,
                                             double unit, Vec4f& acc) {
    if (!(len > 0.0) || !(s0 == s0) || !(s1 == s1) || tf.count < 1) return;
    // Table positions (unclamped, in double: the range's width may overflow float).
    double g0 = 0.0, g1 = 0.0;
    if (tf.hi > tf.lo) {
        const double scale = double(tf.count - 1) / (double(tf.hi) - double(tf.lo));
        g0 = (double(s0) - tf.lo) * scale;
        g1 = (double(s1) - tf.lo) * scale;
        if (!(fabs(g0) < 1e30) || !(fabs(g1) < 1e30)) {  // infinite values: clamp first
            const double cap = 2.0 * tf.count;
            g0 = g0 > cap ? cap : (g0 < -cap ? -cap : g0);
            g1 = g1 > cap ? cap : (g1 < -cap ? -cap : g1);
        }
    }
    const double last = tf.count - 1;
    const double dg = g1 - g0;
    double u = 0.0;  // fraction of the segment done
    Vec4f e0 = tableAt(tf, g0);
    for (int guard = 0; guard <= 2 * tf.count + 4 && u < 1.0; ++guard) {
        if (acc.w >= kExactOpacityEnd) return;
        // Next breakpoint: the next whole table position (or range end) in the direction of g.
        const double g = g0 + dg * u;
        double uNext = 1.0;
        if (dg > 0.0 && g < last) {
            const double target = g < 0.0 ? 0.0 : floor(g) + 1.0;
            uNext = (target - g0) / dg;
        } else if (dg < 0.0 && g > 0.0) {
            const double target = g > last ? last : ceil(g) - 1.0;
            uNext = (target - g0) / dg;
        }
        if (!(uNext > u)) uNext = u + 1e-12;  // rounding at a breakpoint: always advance
        if (uNext > 1.0) uNext = 1.0;
        const Vec4f e1 = tableAt(tf, g0 + dg * uNext);
        compositePiece(e0.xyz(), e0.w, e1.xyz(), e1.w, (uNext - u) * len, unit, acc);
        e0 = e1;
        u = uNext;
    }
}

/// The span [tIn, tOut] of a ray inside a tetrahedron and the face (opposite vertex exitFace)
/// through which it leaves; empty when tIn > tOut.
struct TetSpan {
    double tIn = -INFINITY, tOut = INFINITY;
    int exitFace = -1;
};

/// Clips the ray against the four face planes of tetrahedron t (in double; either orientation).
UVR_HOST_DEVICE inline TetSpan clipTet(const TetMeshView& mesh, std::uint32_t t, const Ray& ray) {
    const Tet& tet = mesh.tets[t];
    Vec3d p[4];
    for (int i = 0; i < 4; ++i) p[i] = toDouble(mesh.points[tet.v[i]]);
    const Vec3d o = toDouble(ray.org), d = toDouble(ray.dir);
    TetSpan s;
    for (int i = 0; i < 4; ++i) {
        // Face opposite vertex i; its normal points away from vertex i.
        const Vec3d a = p[(i + 1) & 3], b = p[(i + 2) & 3], c = p[(i + 3) & 3];
        Vec3d n = cross(b - a, c - a);
        if (dot(n, p[i] - a) > 0.0) n = {-n.x, -n.y, -n.z};
        const double num = dot(n, a - o), den = dot(n, d);
        if (den > 0.0) {
            const double t1 = num / den;
            if (t1 < s.tOut) s.tOut = t1, s.exitFace = i;
        } else if (den < 0.0) {
            const double t0 = num / den;
            if (t0 > s.tIn) s.tIn = t0;
        } else if (num < 0.0) {  // parallel to the face and outside it
            s.tIn = INFINITY;
            s.tOut = -INFINITY;
        }
    }
    return s;
}

/// The tetrahedron the ray is in just after t (entered last among those it is in, or the
/// nearest ahead): over the BVH's tetrahedra with tOut > t + eps, the one whose max(tIn, t) is
/// smallest (ties: the larger tOut). kNoTet when no tetrahedron lies ahead.
UVR_HOST_DEVICE inline std::uint32_t nextTetAlong(const TetMeshView& mesh, const BvhView& bvh,
                                                  const Ray& ray, double t, double eps,
                                                  TetSpan& span, RayCounters& counters) {
    ++counters.locate.bvhQueries;
    std::uint32_t best = kNoTet;
    double bestKey = INFINITY, bestOut = -INFINITY;
    if (bvh.nodeCount == 0) return best;
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    std::uint32_t stack[2 * kBvhMaxDepth + 2];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const BvhNode& node = bvh.nodes[stack[--top]];
        float b0 = static_cast<float>(t) - static_cast<float>(eps), b1 = INFINITY;
        // Boxes grown a little: a tetrahedron's face may lie on its box's face.
        Bounds3f box = node.box;
        const Vec3f grow = box.extent() * 1e-5f + Vec3f(1e-30f);
        box.lo = box.lo - grow;
        box.hi = box.hi + grow;
        if (!intersectBox(box, ray.org, inv, b0, b1)) continue;
        if (b0 > bestKey) continue;
        if (node.count > 0) {
            for (std::uint32_t k = 0; k < node.count; ++k) {
                const std::uint32_t id = bvh.primIds[node.first + k];
                const TetSpan s = clipTet(mesh, id, ray);
                if (!(s.tOut > t + eps) || !(s.tIn <= s.tOut)) continue;
                const double key = s.tIn > t ? s.tIn : t;
                if (key < bestKey || (key == bestKey && s.tOut > bestOut)) {
                    best = id, bestKey = key, bestOut = s.tOut, span = s;
                }
            }
        } else if (top + 2 <= 2 * kBvhMaxDepth + 2) {
            stack[top++] = node.first;
            stack[top++] = node.first + 1;
        }
    }
    return best;
}

/// Scalar at parameter t of the ray inside tetrahedron tet (barycentric, clamped to the cell).
UVR_HOST_DEVICE inline float scalarAt(const TetLocator& loc, std::uint32_t tet, const Ray& ray,
                                      double t) {
    const TetMeshView& m = loc.mesh;
    if (m.cellCentered) return m.values[tet];
    const Tet& c = m.tets[tet];
    float bary[4];
    const Vec3f p = ray.at(static_cast<float>(t));
    if (!tetBarycentrics(p, m.points[c.v[0]], m.points[c.v[1]], m.points[c.v[2]], m.points[c.v[3]],
                         bary))
        for (float& b : bary) b = 0.25f;  // a degenerate tetrahedron: the mean of its corners
    float sum = 0.f;
    for (float& b : bary) b = b > 0.f ? b : 0.f, sum += b;
    if (sum > 0.f)
        for (float& b : bary) b /= sum;
    return m.interpolate(tet, bary);
}

}  // namespace exact

/// The exact integrator for one ray (see the top of this file).
UVR_HOST_DEVICE inline Vec4f integrateExact(const SceneView& scene, const Ray& ray,
                                            RayCounters& counters) {
    Vec4f acc(0.f, 0.f, 0.f, 0.f);
    if (scene.bounds.empty()) return acc;
    const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
    float b0 = 0.f, b1 = INFINITY;
    if (!intersectBox(scene.bounds, ray.org, inv, b0, b1)) return acc;
    const TetLocator& loc = scene.locator;
    // A gap this small between tetrahedra is rounding, not empty space.
    const double eps = 1e-6 * (double(scene.bounds.diagonal()) + double(b0));
    const double unit = scene.params.opacityUnit;
    double t = b0;
    exact::TetSpan span;
    std::uint32_t tet = exact::nextTetAlong(loc.mesh, loc.bvh, ray, t, eps, span, counters);
    if (tet != kNoTet && span.tIn > t) t = span.tIn;  // empty space before the mesh
    for (std::uint32_t step = 0; tet != kNoTet && step < kExactMaxSteps; ++step) {
        const double tEnd = span.tOut;
        if (tEnd > t) {
            ++counters.samples;  // one segment per tetrahedron crossed
            const float s0 = exact::scalarAt(loc, tet, ray, t);
            const float s1 = exact::scalarAt(loc, tet, ray, tEnd);
            exact::integrateSegment(scene.tf, s0, s1, tEnd - t, unit, acc);
            if (acc.w >= kExactOpacityEnd) break;
            t = tEnd;
        }
        // Across the exit face; located again where there is no neighbour or the crossing is
        // degenerate (the neighbour's span does not continue the ray).
        const std::uint32_t next =
            loc.neighbors && span.exitFace >= 0 ? loc.neighbors[4 * tet + span.exitFace] : kNoTet;
        if (next != kNoTet) {
            const exact::TetSpan s = exact::clipTet(loc.mesh, next, ray);
            if (s.tOut > t + eps && s.tIn <= t + eps) {
                tet = next;
                span = s;
                continue;
            }
        }
        tet = exact::nextTetAlong(loc.mesh, loc.bvh, ray, t, eps, span, counters);
        if (tet != kNoTet && span.tIn > t) t = span.tIn;  // empty space before it
    }
    return acc;
}

}  // namespace uvr

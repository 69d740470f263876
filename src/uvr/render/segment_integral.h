// SPDX-License-Identifier: MIT
#pragma once

// Emission-absorption over a segment along which the scalar runs linearly (issue 11): the exact
// integrator calls it once per tetrahedron crossed, the sample-based methods once per step
// between consecutive samples (pre-integration: a transfer-function feature between two samples
// is integrated, never missed).
//
// A transfer-function opacity alpha per opacity unit u is an extinction kappa(s) by the table's
// OpacityLaw: alpha / u (attenuation, ParaView's unstructured mappers) or -ln(1 - alpha) / u
// (transmittance: the point samplers' opacity correction 1 - (1 - alpha)^(step / u) is exactly
// exp(-kappa step)); the emission is c(s) kappa(s). The transfer function is the baked table,
// linear between its breakpoints (tfTableBreaks). So a segment splits at the breakpoints it
// crosses into pieces where colour and opacity are linear in the distance t:
// - the optical depth of a piece is closed-form: under attenuation kappa is linear, the depth
//   quadratic, t (alpha(0) + alpha(t)) / (2 u); under transmittance, with w(t) = 1 - alpha(t)
//   linear, integral of -ln w dt = t * (-(F(w) - F(w0)) / (w - w0)), F(w) = w ln w - w;
// - the colour is integrated by parts, c kappa T = -c dT/dt with c linear: c0 - c1 T(L) + c' *
//   integral of T, and the mean transmittance of the piece by composite Gauss-Legendre quadrature
//   of the closed-form T (smooth and monotone), to about 1e-9.

#include <cfloat>
#include <cmath>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"
#include "uvr/tf/tf_table.h"

namespace uvr {
namespace segment {

/// Accumulated opacity at which a segment's integration stops (what is left changes a pixel by
/// less than 1e-6).
inline constexpr float kOpacityEnd = 0.999999f;

/// (F(w1) - F(w0)) / (w1 - w0) for F(w) = w ln w - w: the mean of ln w over [w0, w1] (w >= 0).
UVR_HOST_DEVICE inline double meanLog(double w0, double w1) {
    const double d = w1 - w0;
    if (fabs(d) <= 1e-7 * fmax(w0, w1)) return log(0.5 * (w0 + w1));
    auto F = [](double w) { return w > 0.0 ? w * log(w) - w : 0.0; };
    return (F(w1) - F(w0)) / d;
}

/// Optical depth from 0 to t of a piece of length len whose opacity runs linearly from a0 to a1
/// (in [0, 1]; under transmittance both below 1 or one of them 1), per opacity unit `unit`.
UVR_HOST_DEVICE inline double opticalDepth(double a0, double a1, double len, double t, double unit,
                                           OpacityLaw law) {
    if (t <= 0.0) return 0.0;
    const double at = a0 + (a1 - a0) * (t / len);
    if (law == OpacityLaw::Attenuation) return t * 0.5 * (a0 + at) / unit;
    const double wt = 1.0 - at;
    return -t * meanLog(1.0 - a0, wt > 0.0 ? wt : 0.0) / unit;
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
                                                double tauEnd, OpacityLaw law) {
    double tStop = len;
    if (tauEnd > 40.0) {
        double lo = 0.0, hi = len;  // tau is increasing: bisect tau(t) = 40
        for (int i = 0; i < 60; ++i) {
            const double mid = 0.5 * (lo + hi);
            (opticalDepth(a0, a1, len, mid, unit, law) < 40.0 ? lo : hi) = mid;
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
                wgt[k] * 0.5 * h * exp(-opticalDepth(a0, a1, len, mid + 0.5 * h * x[k], unit, law));
    }
    return integral / len;
}

/// Composites a piece of length len, colour and opacity linear from c0, a0 to c1, a1, into the
/// premultiplied accumulator (front to back), opacity read by `law`.
UVR_HOST_DEVICE inline void compositePiece(Vec3f c0, double a0, Vec3f c1, double a1, double len,
                                           double unit, OpacityLaw law, Vec4f& acc) {
    if (!(len > 0.0)) return;
    a0 = a0 > 0.0 ? (a0 < 1.0 ? a0 : 1.0) : 0.0;
    a1 = a1 > 0.0 ? (a1 < 1.0 ? a1 : 1.0) : 0.0;
    if (a0 == 0.0 && a1 == 0.0) return;
    const double remaining = 1.0 - acc.w;
    if (law == OpacityLaw::Transmittance && a0 >= 1.0 && a1 >= 1.0) {
        // Infinite extinction: opaque at once.
        acc.x += static_cast<float>(remaining * c0.x);
        acc.y += static_cast<float>(remaining * c0.y);
        acc.z += static_cast<float>(remaining * c0.z);
        acc.w = 1.f;
        return;
    }
    const double tauEnd = opticalDepth(a0, a1, len, len, unit, law);
    const double transEnd = exp(-tauEnd);
    const double mean = a0 == a1 ? meanTransmittanceConstant(tauEnd)
                                 : meanTransmittance(a0, a1, len, unit, tauEnd, law);
    // Colour by parts: c0 (1 - M) + c1 (M - T(len)).
    const double k0 = remaining * (1.0 - mean), k1 = remaining * (mean - transEnd);
    acc.x += static_cast<float>(k0 * c0.x + k1 * c1.x);
    acc.y += static_cast<float>(k0 * c0.y + k1 * c1.y);
    acc.z += static_cast<float>(k0 * c0.z + k1 * c1.z);
    acc.w = static_cast<float>(1.0 - remaining * transEnd);
}

/// F(w) = w ln w - w in float (0 at w = 0).
UVR_HOST_DEVICE inline float entropyF(float w) {
    return w > 0.f ? w * logf(w) - w : 0.f;
}

/// meanLog in float, given f0 = entropyF(w0): the mean of ln w over [w0, w1] (w >= 0).
/// Near-equal ends use the series ln m - (d / m)^2 / 24 (the next term, (d / m)^4 / 320, is
/// below 3e-7 for |d| <= 0.1 m).
UVR_HOST_DEVICE inline float meanLogF(float w0, float f0, float w1) {
    const float d = w1 - w0, m = 0.5f * (w0 + w1);
    if (fabsf(d) <= 0.1f * m) {
        const float r = d / m;
        return logf(m) - r * r * (1.f / 24.f);
    }
    return (entropyF(w1) - f0) / d;
}

/// Largest optical depth of a piece compositePieceFast integrates itself (16 sub-intervals);
/// beyond it (a transmittance below 3e-4 across one piece) it calls compositePiece.
inline constexpr float kFastMaxDepth = 8.f;

/// Most sub-intervals of compositePieceFast's quadrature.
inline constexpr int kFastMaxParts = 16;

/// compositePiece in float for the sample-based methods: the optical depth in closed form (as
/// compositePiece), the mean transmittance by composite 3-point Gauss-Legendre quadrature over
/// sub-intervals of at most about 0.5 optical depth (at most 16). Within 1e-3 of compositePiece;
/// pieces deeper than kFastMaxDepth call it.
UVR_HOST_DEVICE inline void compositePieceFast(Vec3f c0, float a0, Vec3f c1, float a1, float len,
                                               float unit, OpacityLaw law, Vec4f& acc) {
    a0 = a0 > 0.f ? (a0 < 1.f ? a0 : 1.f) : 0.f;
    a1 = a1 > 0.f ? (a1 < 1.f ? a1 : 1.f) : 0.f;
    if (a0 == 0.f && a1 == 0.f) return;
    if (!(len > 0.f)) return;
    const bool attenuation = law == OpacityLaw::Attenuation;
    const float w0 = 1.f - a0, w1 = 1.f - a1;
    const float scale = len / unit;
    // Attenuation: tau(u) = scale u (a0 + (a1 - a0) u / 2); transmittance: tau(u) = -scale u
    // meanLog(w0, w(u)).
    const float f0 = attenuation ? 0.f : entropyF(w0);
    const float tauEnd = attenuation ? scale * 0.5f * (a0 + a1) : -scale * meanLogF(w0, f0, w1);
    if (!(tauEnd <= kFastMaxDepth) || (!attenuation && w0 == 0.f && w1 == 0.f)) {
        compositePiece(c0, a0, c1, a1, len, unit, law, acc);
        return;
    }
    const float transEnd = expf(-tauEnd);
    float mean;
    if (a0 == a1) {
        mean = tauEnd > 1e-6f ? -expm1f(-tauEnd) / tauEnd : 1.f - 0.5f * tauEnd;
    } else {
        // Composite 3-point Gauss-Legendre over n sub-intervals (no node at the ends, where the
        // transmittance law's extinction -ln w may be singular); n from the larger extinction at
        // the ends, so no sub-interval is deeper than about 0.5 (at most kFastMaxParts).
        const float kMax = attenuation ? fmaxf(a0, a1) : -logf(fmaxf(fminf(w0, w1), 1e-30f));
        const float parts = ceilf(2.f * scale * kMax);
        const int n = parts <= 1.f ? 1 : (parts < kFastMaxParts ? int(parts) : kFastMaxParts);
        const float h = 1.f / static_cast<float>(n);
        const float x[3] = {0.1127016654f, 0.5f, 0.8872983346f};
        const float wgt[3] = {5.f / 18.f, 8.f / 18.f, 5.f / 18.f};
        const float halfSlope = 0.5f * (a1 - a0);
        float sum = 0.f;
        for (int j = 0; j < n; ++j)
            for (int q = 0; q < 3; ++q) {
                const float u = (static_cast<float>(j) + x[q]) * h;
                float logT;
                if (attenuation) {
                    logT = -scale * u * (a0 + halfSlope * u);
                } else {
                    const float w = w0 + (w1 - w0) * u;
                    logT = scale * u * meanLogF(w0, f0, w > 0.f ? w : 0.f);
                }
                sum += wgt[q] * expf(logT);
            }
        mean = sum * h;
    }
    const float remaining = 1.f - acc.w;
    const float k0 = remaining * (1.f - mean), k1 = remaining * (mean - transEnd);
    acc.x += k0 * c0.x + k1 * c1.x;
    acc.y += k0 * c0.y + k1 * c1.y;
    acc.z += k0 * c0.z + k1 * c1.z;
    acc.w = 1.f - remaining * transEnd;
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
/// through the transfer function (its opacities read by tf.law), split at the table's breakpoints
/// it crosses (every entry when the table has none), into acc; fast: each piece by
/// compositePieceFast (in float, what the renderers use), else by compositePiece (in double). A NaN
/// end makes the whole segment take the NaN entry tf.nan (constant; transparent at NaN opacity 0):
/// inside a linear tetrahedron with a NaN vertex the field is NaN everywhere, and between samples
/// the NaN region's edge is placed at the segment's near end, as a point sample there would be.
UVR_HOST_DEVICE inline void integrate(const TfTableView& tf, double s0, double s1, double len,
                                      double unit, Vec4f& acc, bool fast = false) {
    if (!(len > 0.0) || tf.count < 1) return;
    // A NaN end: one constant piece (dg 0) of the NaN entry through the same piece code below
    // (a separate branch with its own inlined piece made the GPU kernels spill registers).
    const bool nanEnd = !(s0 == s0) || !(s1 == s1);
    if (nanEnd) s0 = s1 = 0.0;
    // An infinite end is a float overflow of a value near the largest float (interpolating a
    // field that spans the float range): take the largest float.
    s0 = s0 < DBL_MAX ? (s0 > -DBL_MAX ? s0 : -FLT_MAX) : FLT_MAX;
    s1 = s1 < DBL_MAX ? (s1 > -DBL_MAX ? s1 : -FLT_MAX) : FLT_MAX;
    // Table positions (unclamped, in double: the range's width may overflow float).
    double g0 = 0.0, g1 = 0.0;
    if (tf.hi > tf.lo) {
        const double scale = double(tf.count - 1) / (double(tf.hi) - double(tf.lo));
        g0 = (s0 - tf.lo) * scale;
        g1 = (s1 - tf.lo) * scale;
        if (!(fabs(g0) < 1e30) || !(fabs(g1) < 1e30)) {  // infinite values: clamp first
            const double cap = 2.0 * tf.count;
            g0 = g0 > cap ? cap : (g0 < -cap ? -cap : g0);
            g1 = g1 > cap ? cap : (g1 < -cap ? -cap : g1);
        }
    }
    const double last = tf.count - 1;
    const double dg = g1 - g0;
    double u = 0.0;  // fraction of the segment done
    Vec4f e0 = nanEnd ? tf.nan : tableAt(tf, g0);
    for (int guard = 0; guard <= 2 * tf.count + 4 && u < 1.0; ++guard) {
        if (acc.w >= kOpacityEnd) return;
        // Next breakpoint: the next whole table position (or range end) in the direction of g.
        const double g = g0 + dg * u;
        double uNext = 1.0;
        if (dg > 0.0 && g < last) {
            const double target = g < 0.0 ? 0.0 : double(tf.breakAbove(g));
            uNext = (target - g0) / dg;
        } else if (dg < 0.0 && g > 0.0) {
            const double target = g > last ? last : double(tf.breakBelow(g));
            uNext = (target - g0) / dg;
        }
        if (!(uNext > u)) uNext = u + 1e-12;  // rounding at a breakpoint: always advance
        if (uNext > 1.0) uNext = 1.0;
        // A constant value (dg 0, also a NaN end) keeps its entry: no second lookup, and no
        // flag live across the loop.
        const Vec4f e1 = dg == 0.0 ? e0 : tableAt(tf, g0 + dg * uNext);
        // A sliver below 1e-9 of the segment (the forced advance above, or what rounding leaves
        // past the table's last entry when s1 is the range's top) is rounding, not path: at
        // opacity 1 under the transmittance law it would make the ray opaque at once (speckle
        // where a ray ends on a wall at the field's maximum), elsewhere it adds nothing.
        if (uNext - u > 1e-9) {
            if (fast)
                compositePieceFast(e0.xyz(), e0.w, e1.xyz(), e1.w, float((uNext - u) * len),
                                   float(unit), tf.law, acc);
            else
                compositePiece(e0.xyz(), e0.w, e1.xyz(), e1.w, (uNext - u) * len, unit, tf.law,
                               acc);
        }
        e0 = e1;
        u = uNext;
    }
}

}  // namespace segment
}  // namespace uvr

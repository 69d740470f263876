// SPDX-License-Identifier: MIT
#pragma once

// Random native cells for the tests of cell_math.h and cell_clip.h: reference cells, random
// affine images (mirrored ones too) and jittered corners.

#include <cmath>
#include <random>

#include "uvr/core/vec3d.h"
#include "uvr/mesh/cell_math.h"

namespace uvr::celltest {

/// The tests' random generator.
using Rng = std::mt19937;

/// The four cell kinds, for loops.
inline constexpr CellKind kKinds[4] = {CellKind::Tet, CellKind::Pyramid, CellKind::Wedge,
                                       CellKind::Hex};

/// A uniform float in [lo, hi).
/// A kind's name for test messages.
inline const char* kindName(CellKind k) {
    return k == CellKind::Tet       ? "tet"
           : k == CellKind::Pyramid ? "pyramid"
           : k == CellKind::Wedge   ? "wedge"
                                    : "hex";
}

inline float uniform(Rng& rng, float lo, float hi) {
    return std::uniform_real_distribution<float>(lo, hi)(rng);
}

/// The reference cell of kind k (corners at their parametric coordinates: positive Jacobian).
inline void referenceCell(CellKind k, Vec3f* x) {
    for (int i = 0; i < kindCorners(k); ++i) x[i] = cornerParametric(k, i);
}

/// An affine map p -> m p + b.
struct Affine {
    double m[3][3];
    Vec3d b;

    /// The image of p.
    Vec3f apply(Vec3f p) const {
        const double q[3] = {p.x, p.y, p.z};
        double r[3];
        for (int i = 0; i < 3; ++i) r[i] = m[i][0] * q[0] + m[i][1] * q[1] + m[i][2] * q[2];
        return Vec3f(float(r[0] + b.x), float(r[1] + b.y), float(r[2] + b.z));
    }
    /// The determinant of m.
    double det() const {
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    }
};

/// A random rotation times scales in [0.5, 2] times a shear of up to 0.3, mirrored (det < 0) when
/// mirror, moved by up to 5.
inline Affine randomAffine(Rng& rng, bool mirror) {
    double qw = uniform(rng, -1, 1), qx = uniform(rng, -1, 1), qy = uniform(rng, -1, 1),
           qz = uniform(rng, -1, 1);
    const double len = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
    qw /= len, qx /= len, qy /= len, qz /= len;
    const double rot[3][3] = {
        {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)},
        {2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)},
        {2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)}};
    double shear[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    shear[0][1] = uniform(rng, -0.3f, 0.3f);
    shear[1][2] = uniform(rng, -0.3f, 0.3f);
    shear[0][2] = uniform(rng, -0.3f, 0.3f);
    const double scale[3] = {uniform(rng, 0.5f, 2.f) * (mirror ? -1.0 : 1.0),
                             uniform(rng, 0.5f, 2.f), uniform(rng, 0.5f, 2.f)};
    Affine a{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int l = 0; l < 3; ++l) a.m[i][j] += rot[i][l] * scale[l] * shear[l][j];
    a.b = {uniform(rng, -5, 5), uniform(rng, -5, 5), uniform(rng, -5, 5)};
    return a;
}

/// Moves each corner by up to amp in each coordinate.
inline void jitter(Rng& rng, Vec3f* x, int n, float amp) {
    for (int i = 0; i < n; ++i)
        x[i] += Vec3f(uniform(rng, -amp, amp), uniform(rng, -amp, amp), uniform(rng, -amp, amp));
}

/// A random cell of kind k: the reference cell jittered by up to amp, then a random affine map
/// (mirrored when mirror).
inline void randomCell(Rng& rng, CellKind k, float amp, bool mirror, Vec3f* x) {
    referenceCell(k, x);
    jitter(rng, x, kindCorners(k), amp);
    const Affine a = randomAffine(rng, mirror);
    for (int i = 0; i < kindCorners(k); ++i) x[i] = a.apply(x[i]);
}

/// Random parametric coordinates inside kind k's reference cell, at least margin from its faces
/// (pyramids: t <= 0.8, away from the apex where r and s are undetermined).
inline Vec3f randomParametric(Rng& rng, CellKind k, float margin) {
    for (;;) {
        const Vec3f p(uniform(rng, margin, 1 - margin), uniform(rng, margin, 1 - margin),
                      uniform(rng, margin, k == CellKind::Pyramid ? 0.8f : 1 - margin));
        float excess;
        worstFace(k, p, excess);
        if (excess <= -margin) return p;
    }
}

/// The isoparametric map at rst (in double): sum of w_i x_i.
inline Vec3d mapPoint(CellKind k, const Vec3f* x, Vec3f rst) {
    float w[kMaxCellCorners];
    shapeFunctions(k, rst.x, rst.y, rst.z, w);
    Vec3d p;
    for (int i = 0; i < kindCorners(k); ++i) p = p + toDouble(x[i]) * double(w[i]);
    return p;
}

/// The largest coordinate difference between two corners of the cell.
inline double cellSize(CellKind k, const Vec3f* x) {
    double size = 0;
    for (int i = 0; i < kindCorners(k); ++i)
        for (int j = 0; j < i; ++j)
            for (int a = 0; a < 3; ++a)
                size = std::fmax(size, std::fabs(double(x[i][a]) - x[j][a]));
    return size;
}

/// The float point of a double one.
inline Vec3f toFloat(Vec3d p) {
    return Vec3f(float(p.x), float(p.y), float(p.z));
}

/// The interpolation of corner values v at rst.
inline double interpolate(CellKind k, const float* v, Vec3f rst) {
    float w[kMaxCellCorners];
    shapeFunctions(k, rst.x, rst.y, rst.z, w);
    double f = 0;
    for (int i = 0; i < kindCorners(k); ++i) f += double(w[i]) * v[i];
    return f;
}

}  // namespace uvr::celltest

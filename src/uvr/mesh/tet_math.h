// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// Six times the signed volume of tetrahedron (a, b, c, d): det(b - a, c - a, d - a); positive
/// when a, b, c are counter-clockwise seen from d's opposite side (VTK's positive orientation).
UVR_HOST_DEVICE inline float signedVolume6(Vec3f a, Vec3f b, Vec3f c, Vec3f d) {
    return dot(b - a, cross(c - a, d - a));
}

/// Barycentric coordinates of p in a positively oriented tetrahedron (a, b, c, d), computed as
/// ratios of sub-volumes relative to a (for precision); bary[i] weighs vertex i. Returns false
/// for a degenerate (zero-volume) tetrahedron.
UVR_HOST_DEVICE UVR_INLINE bool tetBarycentrics(Vec3f p, Vec3f a, Vec3f b, Vec3f c, Vec3f d,
                                                float bary[4]) {
    const Vec3f ab = b - a, ac = c - a, ad = d - a, ap = p - a;
    const Vec3f cAcAd = cross(ac, ad);
    const float vol = dot(ab, cAcAd);
    if (!(vol > 0.f)) return false;
    const float inv = 1.f / vol;
    bary[1] = dot(ap, cAcAd) * inv;
    bary[2] = dot(ab, cross(ap, ad)) * inv;
    bary[3] = dot(ab, cross(ac, ap)) * inv;
    bary[0] = 1.f - bary[1] - bary[2] - bary[3];
    return true;
}

/// Gradient of the linear function taking values va..vd at the corners of tetrahedron (a, b, c,
/// d): the solution g of (b - a) . g = vb - va, (c - a) . g = vc - va, (d - a) . g = vd - va, by
/// Cramer's rule. Non-finite for a degenerate tetrahedron.
UVR_HOST_DEVICE inline Vec3f tetGradient(Vec3f a, Vec3f b, Vec3f c, Vec3f d, float va, float vb,
                                         float vc, float vd) {
    const Vec3f e1 = b - a, e2 = c - a, e3 = d - a;
    const Vec3f n1 = cross(e2, e3), n2 = cross(e3, e1), n3 = cross(e1, e2);
    const float inv = 1.f / dot(e1, n1);
    return (n1 * (vb - va) + n2 * (vc - va) + n3 * (vd - va)) * inv;
}

/// Tolerance on barycentric coordinates for "p lies in the tetrahedron": points within this
/// relative distance outside a face still count, so points on shared faces never fall between
/// neighbours because of rounding.
inline constexpr float kBaryEpsilon = 1e-5f;

}  // namespace uvr

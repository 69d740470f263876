// SPDX-License-Identifier: MIT
#pragma once

// Element math of the native cells (issue 14): pyramids, wedges and hexahedra sampled in their own
// interpolation (VTK's shape functions over parametric coordinates r, s, t), with the inverse of
// the isoparametric map by Newton's method, so a hexahedron is trilinear with non-planar faces
// (bilinear patches) instead of six linear tetrahedra. Tetrahedra use the same interface with
// r, s, t their barycentrics 1..3. Shared by the CPU and the GPU.

#include <cmath>
#include <cstdint>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// The kinds of rendered cells, in the order their ids are numbered (TetMeshView).
enum class CellKind : std::uint8_t { Tet = 0, Pyramid = 1, Wedge = 2, Hex = 3 };

/// Corners of a cell kind (4, 5, 6, 8).
UVR_HOST_DEVICE constexpr int kindCorners(CellKind k) {
    return k == CellKind::Tet ? 4 : k == CellKind::Pyramid ? 5 : k == CellKind::Wedge ? 6 : 8;
}

/// Faces of a cell kind (4, 5, 5, 6).
UVR_HOST_DEVICE constexpr int kindFaces(CellKind k) {
    return k == CellKind::Tet ? 4 : k == CellKind::Hex ? 6 : 5;
}

/// Most corners of a cell, most faces of a cell.
inline constexpr int kMaxCellCorners = 8;
inline constexpr int kMaxCellFaces = 6;

namespace cellface {
/// A face packed as four 4-bit local corner indices (low first) and its corner count in bits
/// 16-18.
UVR_HOST_DEVICE constexpr std::uint32_t pack(int a, int b, int c, int d = 0, int n = 4) {
    return std::uint32_t(a) | std::uint32_t(b) << 4 | std::uint32_t(c) << 8 |
           std::uint32_t(d) << 12 | std::uint32_t(n) << 16;
}
}  // namespace cellface

/// Face f of a cell kind, packed (cellface::pack). Corners are ordered so that the right-hand
/// normal points out of a cell whose isoparametric map has a positive Jacobian. Tetrahedra: face
/// f is opposite corner f. Hexahedra: faces r = 0, r = 1, s = 0, s = 1, t = 0, t = 1. Wedges:
/// t = 0, t = 1, s = 0, r + s = 1, r = 0. Pyramids: the base t = 0, then s = 0, r = 1, s = 1,
/// r = 0.
UVR_HOST_DEVICE inline std::uint32_t packedFace(CellKind k, int f) {
    using cellface::pack;
    switch (k) {
        case CellKind::Tet:
            return f == 0   ? pack(1, 2, 3, 0, 3)
                   : f == 1 ? pack(0, 3, 2, 0, 3)
                   : f == 2 ? pack(0, 1, 3, 0, 3)
                            : pack(0, 2, 1, 0, 3);
        case CellKind::Pyramid:
            return f == 0   ? pack(0, 3, 2, 1)
                   : f == 1 ? pack(0, 1, 4, 0, 3)
                   : f == 2 ? pack(1, 2, 4, 0, 3)
                   : f == 3 ? pack(2, 3, 4, 0, 3)
                            : pack(3, 0, 4, 0, 3);
        case CellKind::Wedge:
            return f == 0   ? pack(0, 2, 1, 0, 3)
                   : f == 1 ? pack(3, 4, 5, 0, 3)
                   : f == 2 ? pack(0, 1, 4, 3)
                   : f == 3 ? pack(1, 2, 5, 4)
                            : pack(0, 3, 5, 2);
        case CellKind::Hex:
        default:
            return f == 0   ? pack(0, 4, 7, 3)
                   : f == 1 ? pack(1, 2, 6, 5)
                   : f == 2 ? pack(0, 1, 5, 4)
                   : f == 3 ? pack(3, 7, 6, 2)
                   : f == 4 ? pack(0, 3, 2, 1)
                            : pack(4, 5, 6, 7);
    }
}

/// Corner count (3 or 4) of a packed face.
UVR_HOST_DEVICE constexpr int faceSize(std::uint32_t packed) {
    return int(packed >> 16) & 7;
}
/// Local corner i of a packed face.
UVR_HOST_DEVICE constexpr int faceCorner(std::uint32_t packed, int i) {
    return int(packed >> (4 * i)) & 15;
}

/// Shape functions (VTK's) of kind k at parametric (r, s, t) into w[0..corners-1], and with
/// dr/ds/dt non-null their derivatives.
UVR_HOST_DEVICE inline void shapeFunctions(CellKind k, float r, float s, float t, float* w,
                                           float* dr = nullptr, float* ds = nullptr,
                                           float* dt = nullptr) {
    const float rm = 1.f - r, sm = 1.f - s, tm = 1.f - t;
    switch (k) {
        case CellKind::Tet:
            w[0] = 1.f - r - s - t, w[1] = r, w[2] = s, w[3] = t;
            if (dr) {
                dr[0] = -1.f, dr[1] = 1.f, dr[2] = 0.f, dr[3] = 0.f;
                ds[0] = -1.f, ds[1] = 0.f, ds[2] = 1.f, ds[3] = 0.f;
                dt[0] = -1.f, dt[1] = 0.f, dt[2] = 0.f, dt[3] = 1.f;
            }
            return;
        case CellKind::Pyramid:
            w[0] = rm * sm * tm, w[1] = r * sm * tm, w[2] = r * s * tm, w[3] = rm * s * tm;
            w[4] = t;
            if (dr) {
                dr[0] = -sm * tm, dr[1] = sm * tm, dr[2] = s * tm, dr[3] = -s * tm, dr[4] = 0.f;
                ds[0] = -rm * tm, ds[1] = -r * tm, ds[2] = r * tm, ds[3] = rm * tm, ds[4] = 0.f;
                dt[0] = -rm * sm, dt[1] = -r * sm, dt[2] = -r * s, dt[3] = -rm * s, dt[4] = 1.f;
            }
            return;
        case CellKind::Wedge: {
            const float u = 1.f - r - s;
            w[0] = u * tm, w[1] = r * tm, w[2] = s * tm, w[3] = u * t, w[4] = r * t, w[5] = s * t;
            if (dr) {
                dr[0] = -tm, dr[1] = tm, dr[2] = 0.f, dr[3] = -t, dr[4] = t, dr[5] = 0.f;
                ds[0] = -tm, ds[1] = 0.f, ds[2] = tm, ds[3] = -t, ds[4] = 0.f, ds[5] = t;
                dt[0] = -u, dt[1] = -r, dt[2] = -s, dt[3] = u, dt[4] = r, dt[5] = s;
            }
            return;
        }
        case CellKind::Hex:
        default:
            w[0] = rm * sm * tm, w[1] = r * sm * tm, w[2] = r * s * tm, w[3] = rm * s * tm;
            w[4] = rm * sm * t, w[5] = r * sm * t, w[6] = r * s * t, w[7] = rm * s * t;
            if (dr) {
                dr[0] = -sm * tm, dr[1] = sm * tm, dr[2] = s * tm, dr[3] = -s * tm;
                dr[4] = -sm * t, dr[5] = sm * t, dr[6] = s * t, dr[7] = -s * t;
                ds[0] = -rm * tm, ds[1] = -r * tm, ds[2] = r * tm, ds[3] = rm * tm;
                ds[4] = -rm * t, ds[5] = -r * t, ds[6] = r * t, ds[7] = rm * t;
                dt[0] = -rm * sm, dt[1] = -r * sm, dt[2] = -r * s, dt[3] = -rm * s;
                dt[4] = rm * sm, dt[5] = r * sm, dt[6] = r * s, dt[7] = rm * s;
            }
            return;
    }
}

/// Parametric coordinates of corner i of kind k (the apex of a pyramid: (0.5, 0.5, 1)).
UVR_HOST_DEVICE inline Vec3f cornerParametric(CellKind k, int i) {
    if (k == CellKind::Tet) return {i == 1 ? 1.f : 0.f, i == 2 ? 1.f : 0.f, i == 3 ? 1.f : 0.f};
    if (k == CellKind::Wedge) {
        const int j = i % 3;
        return {j == 1 ? 1.f : 0.f, j == 2 ? 1.f : 0.f, i >= 3 ? 1.f : 0.f};
    }
    if (k == CellKind::Pyramid && i == 4) return {0.5f, 0.5f, 1.f};
    const int j = i & 3;
    return {(j == 1 || j == 2) ? 1.f : 0.f, j >= 2 ? 1.f : 0.f, i >= 4 ? 1.f : 0.f};
}

/// Parametric centre of kind k (where Newton's method starts).
UVR_HOST_DEVICE inline Vec3f cellCentreParametric(CellKind k) {
    switch (k) {
        case CellKind::Tet:
            return {0.25f, 0.25f, 0.25f};
        case CellKind::Pyramid:
            return {0.5f, 0.5f, 0.2f};
        case CellKind::Wedge:
            return {1.f / 3.f, 1.f / 3.f, 0.5f};
        case CellKind::Hex:
        default:
            return {0.5f, 0.5f, 0.5f};
    }
}

/// The isoparametric map's value (relative to corner 0) and Jacobian columns at (r, s, t):
/// x - x0 = sum w_i e_i with e_i = x_i - x_0 (e[0] = 0), columns dx/dr, dx/ds, dx/dt.
UVR_HOST_DEVICE inline void cellMap(CellKind k, const Vec3f* e, Vec3f rst, Vec3f& x, Vec3f& jr,
                                    Vec3f& js, Vec3f& jt) {
    float w[kMaxCellCorners], dr[kMaxCellCorners], ds[kMaxCellCorners], dt[kMaxCellCorners];
    shapeFunctions(k, rst.x, rst.y, rst.z, w, dr, ds, dt);
    x = jr = js = jt = Vec3f(0.f);
    const int n = kindCorners(k);
    for (int i = 1; i < n; ++i) {
        x += e[i] * w[i];
        jr += e[i] * dr[i];
        js += e[i] * ds[i];
        jt += e[i] * dt[i];
    }
}

/// Newton iterations of cellParametric at most.
inline constexpr int kNewtonIterations = 12;
/// cellParametric gives up on a point whose iterate lies more than kNewtonGiveUpOutside outside
/// the parametric unit box after kNewtonGiveUpAfter + 1 steps (it is not in the cell).
inline constexpr int kNewtonGiveUpAfter = 2;
inline constexpr float kNewtonGiveUpOutside = 0.5f;
/// A Newton step at most this long (in parametric units) ends cellParametric: the iterate it
/// gives is within about its square, 1e-6, of the root (below the 1e-5 residual test).
inline constexpr float kNewtonQuadraticStep = 1e-3f;

/// Parametric coordinates rst of point p in the cell of kind k with corners x[0..n-1]: the
/// inverse of the isoparametric map by Newton's method from the parametric centre (or, with
/// fromGuess, from rst as given: a nearby point's coordinates), in
/// coordinates relative to corner 0 (for precision), each step's iterate kept within [-1, 2] (a
/// far point's iteration cannot run away). Returns true when the residual fell below 1e-5 of the
/// cell's size (or a step fell below kNewtonQuadraticStep); false for a point the map does not
/// reach from the centre (far outside a distorted cell, or a singular Jacobian) or whose iterate is
/// still far outside after a few steps (kNewtonGiveUpOutside), with rst the last iterate. Exact for
/// tetrahedra and parallelepipeds in one step; a few steps otherwise.
UVR_HOST_DEVICE inline bool cellParametric(CellKind k, const Vec3f* x, Vec3f p, Vec3f& rst,
                                           bool fromGuess = false) {
    Vec3f e[kMaxCellCorners];
    const int n = kindCorners(k);
    float size = 0.f;
    e[0] = Vec3f(0.f);
    for (int i = 1; i < n; ++i) {
        e[i] = x[i] - x[0];
        size = maxf(size, maxf(fabsf(e[i].x), maxf(fabsf(e[i].y), fabsf(e[i].z))));
    }
    const Vec3f q = p - x[0];
    if (!fromGuess) rst = cellCentreParametric(k);
    const float tol = 1e-5f * size;
    bool converged = false;
    for (int it = 0; it < kNewtonIterations && !converged; ++it) {
        Vec3f f, jr, js, jt;
        cellMap(k, e, rst, f, jr, js, jt);
        f = f - q;
        // Solve J d = -f by Cramer's rule.
        const Vec3f c0 = cross(js, jt);
        const float det = dot(jr, c0);
        if (!(fabsf(det) > 1e-30f)) break;
        const float inv = -1.f / det;
        const Vec3f d(dot(f, c0) * inv, dot(jr, cross(f, jt)) * inv, dot(jr, cross(js, f)) * inv);
        rst = rst + d;
        rst = Vec3f(minf(maxf(rst.x, -1.f), 2.f), minf(maxf(rst.y, -1.f), 2.f),
                    minf(maxf(rst.z, -1.f), 2.f));
        const float residual =
            isFinite(f) ? maxf(fabsf(f.x), maxf(fabsf(f.y), fabsf(f.z))) : INFINITY;
        const float moved = maxf(fabsf(d.x), maxf(fabsf(d.y), fabsf(d.z)));
        // A step this small leaves an error of about its square (Newton converges
        // quadratically): accept the new iterate without another map evaluation.
        converged = residual <= tol || moved <= kNewtonQuadraticStep || !(moved == moved);
        if (!(moved == moved)) return false;  // NaN
        // Far outside after a few steps: not in the cell (a walk needs only the direction, and
        // a point outside may take every iteration to settle).
        const float outside = maxf(maxf(maxf(-rst.x, rst.x - 1.f), maxf(-rst.y, rst.y - 1.f)),
                                   maxf(-rst.z, rst.z - 1.f));
        if (!converged && it >= kNewtonGiveUpAfter && outside > kNewtonGiveUpOutside) return false;
    }
    if (!converged) {  // the last step's residual
        Vec3f f, jr, js, jt;
        cellMap(k, e, rst, f, jr, js, jt);
        f = f - q;
        converged = isFinite(f) && maxf(fabsf(f.x), maxf(fabsf(f.y), fabsf(f.z))) <= tol;
    }
    return converged;
}

/// How far parametric rst lies outside face f of kind k (positive: outside; the faces of
/// packedFace). A pyramid's sides count in units that shrink to 0 at the apex.
UVR_HOST_DEVICE inline float faceExcess(CellKind k, Vec3f rst, int f) {
    const float r = rst.x, s = rst.y, t = rst.z;
    switch (k) {
        case CellKind::Tet:
            return f == 0 ? r + s + t - 1.f : (f == 1 ? -r : (f == 2 ? -s : -t));
        case CellKind::Pyramid: {
            // The sides scaled by 1 - t (as the physical distance to them is): beyond the apex
            // (t > 1) the map mirrors the pyramid, and those points are outside every side.
            const float tm = 1.f - t;
            return f == 0   ? -t
                   : f == 1 ? -s * tm
                   : f == 2 ? (r - 1.f) * tm
                   : f == 3 ? (s - 1.f) * tm
                            : -r * tm;
        }
        case CellKind::Wedge:
            return f == 0 ? -t : (f == 1 ? t - 1.f : (f == 2 ? -s : (f == 3 ? r + s - 1.f : -r)));
        case CellKind::Hex:
        default:
            return f == 0   ? -r
                   : f == 1 ? r - 1.f
                   : f == 2 ? -s
                   : f == 3 ? s - 1.f
                   : f == 4 ? -t
                            : t - 1.f;
    }
}

/// The face of kind k that rst lies furthest outside of (the one a walk crosses), and that
/// excess (<= eps: rst is inside within eps).
UVR_HOST_DEVICE inline int worstFace(CellKind k, Vec3f rst, float& excess) {
    int worst = 0;
    excess = faceExcess(k, rst, 0);
    const int n = kindFaces(k);
    for (int f = 1; f < n; ++f) {
        const float x = faceExcess(k, rst, f);
        if (x > excess) excess = x, worst = f;
    }
    return worst;
}

/// rst moved to the nearest point of kind k's parametric domain, per coordinate (a point found
/// just outside a face by rounding is read on the face, never extrapolated).
UVR_HOST_DEVICE inline Vec3f clampParametric(CellKind k, Vec3f rst) {
    auto unit = [](float v) { return fminf(fmaxf(v, 0.f), 1.f); };
    Vec3f c(unit(rst.x), unit(rst.y), unit(rst.z));
    if (k == CellKind::Wedge && c.x + c.y > 1.f) {
        const float scale = 1.f / (c.x + c.y);
        c.x *= scale, c.y *= scale;
    } else if (k == CellKind::Tet && c.x + c.y + c.z > 1.f) {
        const float scale = 1.f / (c.x + c.y + c.z);
        c = c * scale;
    }
    return c;
}

/// Gradient of the field with corner values v at parametric rst of the cell with corners x:
/// J^-T (df/dr, df/ds, df/dt). Non-finite where the Jacobian is singular.
UVR_HOST_DEVICE inline Vec3f cellGradient(CellKind k, const Vec3f* x, const float* v, Vec3f rst) {
    Vec3f e[kMaxCellCorners];
    const int n = kindCorners(k);
    e[0] = Vec3f(0.f);
    for (int i = 1; i < n; ++i) e[i] = x[i] - x[0];
    float w[kMaxCellCorners], dr[kMaxCellCorners], ds[kMaxCellCorners], dt[kMaxCellCorners];
    shapeFunctions(k, rst.x, rst.y, rst.z, w, dr, ds, dt);
    Vec3f jr(0.f), js(0.f), jt(0.f);
    float fr = 0.f, fs = 0.f, ft = 0.f;
    for (int i = 0; i < n; ++i) {
        jr += e[i] * dr[i], js += e[i] * ds[i], jt += e[i] * dt[i];
        fr += v[i] * dr[i], fs += v[i] * ds[i], ft += v[i] * dt[i];
    }
    // grad = J^-T df: with J's columns jr, js, jt, the rows of J^-1 are the cross products over
    // det; J^-T df = (fr (js x jt) + fs (jt x jr) + ft (jr x js)) / det.
    const float det = dot(jr, cross(js, jt));
    return (cross(js, jt) * fr + cross(jt, jr) * fs + cross(jr, js) * ft) * (1.f / det);
}

/// How far a corner's Jacobian determinant may have the sign opposite to the centre's, relative
/// to the centre's, for the cell to stay native: a corner folded a little (a jittered or sheared
/// grid's cell) keeps the cell native, because splitting it would leave slivers between its
/// planar triangles and its native neighbours' bilinear faces.
inline constexpr double kNativeFold = 0.25;

/// Smallest Jacobian determinant at a native cell's centre, relative to its size cubed: flatter
/// cells are left to the split, whose zero-volume rule (1e-7 of the longest edge cubed) drops
/// them.
inline constexpr double kNativeMinDet = 1e-9;

/// Orientation of a native cell's isoparametric map: +1 or -1, the sign of the Jacobian's
/// determinant at the centre (at least kNativeMinDet of the cell's size cubed), when at every
/// corner (a pyramid's apex, where it vanishes, at t = 0.5 instead) it has that sign or the
/// opposite one by at most kNativeFold of the centre's; 0 for a cell that folds further, collapses
/// or has non-finite corners (it is rendered split into tetrahedra instead).
int nativeOrientation(CellKind k, const Vec3f* x);

}  // namespace uvr

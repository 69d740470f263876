// SPDX-License-Identifier: MIT
#pragma once

// A ray against one native cell (issue 14): the span of the ray inside a tetrahedron, pyramid,
// wedge or hexahedron whose quadrilateral faces are bilinear patches (the cell's isoparametric
// map restricted to the face), so a trilinear hexahedron with non-planar faces is clipped against
// its exact boundary. In double, on the CPU and the GPU.
//
// Each face's crossing is computed from the face's corners alone, put in a canonical order (the
// lexicographically smallest corner first), so two cells sharing a face get the same crossing
// parameter bit for bit, whichever cell asks; only its direction (entering or leaving) differs.

#include <cmath>
#include <cstdint>

#include "uvr/core/host_device.h"
#include "uvr/core/ray.h"
#include "uvr/core/vec3d.h"
#include "uvr/mesh/cell_math.h"

namespace uvr {

/// The span [tIn, tOut] of a ray inside a cell and the face (packedFace's numbering) it leaves
/// through; empty when !(tIn <= tOut).
struct CellSpan {
    double tIn = -INFINITY, tOut = INFINITY;
    int exitFace = -1;
};

namespace cellclip {

/// How far outside [0, 1] a face's parametric coordinates of a crossing may lie (a ray through
/// an edge is caught by both faces that share it).
inline constexpr double kFaceTolerance = 1e-9;
/// Crossings where the ray meets a face at less than this sine of an angle (within its plane, up
/// to rounding) are ignored: their direction is noise.
inline constexpr double kGrazing = 1e-12;

/// Most crossings of a line with a cell's faces (two per bilinear patch).
inline constexpr int kMaxCrossings = 2 * kMaxCellFaces;

/// True when a precedes b lexicographically (x, then y, then z).
UVR_HOST_DEVICE inline bool lexLess(Vec3f a, Vec3f b) {
    return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)));
}

/// Sign of the isoparametric map's Jacobian determinant at the parametric centre (in double): +1,
/// -1, or 0 for a flat or non-finite cell.
UVR_HOST_DEVICE inline int centreOrientation(CellKind k, const Vec3f* x) {
    const Vec3f c = cellCentreParametric(k);
    float w[kMaxCellCorners], dr[kMaxCellCorners], ds[kMaxCellCorners], dt[kMaxCellCorners];
    shapeFunctions(k, c.x, c.y, c.z, w, dr, ds, dt);
    Vec3d jr, js, jt;
    const Vec3d x0 = toDouble(x[0]);
    for (int i = 1; i < kindCorners(k); ++i) {
        const Vec3d e = toDouble(x[i]) - x0;
        jr = jr + e * double(dr[i]), js = js + e * double(ds[i]), jt = jt + e * double(dt[i]);
    }
    const double det = dot(jr, cross(js, jt));
    return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
}

/// A triangle's corners in canonical (lexicographic) order; returns -1 when that order reverses
/// the given one's orientation, else +1.
UVR_HOST_DEVICE inline int canonicalTriangle(Vec3f& a, Vec3f& b, Vec3f& c) {
    int sign = 1;
    Vec3f t;
    if (lexLess(b, a)) t = a, a = b, b = t, sign = -sign;
    if (lexLess(c, b)) t = b, b = c, c = t, sign = -sign;
    if (lexLess(b, a)) t = a, a = b, b = t, sign = -sign;
    return sign;
}

/// A quadrilateral's corners q[0..3] (a cycle) rotated to start at the lexicographically smallest
/// and walked towards its smaller neighbour; returns -1 when that walk reverses the given cycle
/// (the patch's normal flips), else +1.
UVR_HOST_DEVICE inline int canonicalQuad(Vec3f* q) {
    int m = 0;
    for (int i = 1; i < 4; ++i)
        if (lexLess(q[i], q[m])) m = i;
    const bool reverse = lexLess(q[(m + 3) & 3], q[(m + 1) & 3]);
    const Vec3f p[4] = {q[0], q[1], q[2], q[3]};
    for (int i = 0; i < 4; ++i) q[i] = p[(reverse ? m - i + 4 : m + i) & 3];
    return reverse ? -1 : 1;
}

/// The line org + t dir against the plane of triangle a, b, c (canonical order): den = dot(n,
/// dir) and t = num / den with n = (b - a) x (c - a), num = dot(n, a - org).
UVR_HOST_DEVICE inline void trianglePlane(Vec3d a, Vec3d b, Vec3d c, Vec3d o, Vec3d d, Vec3d& n,
                                          double& num, double& den) {
    n = cross(b - a, c - a);
    num = dot(n, a - o);
    den = dot(n, d);
}

/// Whether the direction dir meets a surface with normal n at more than the grazing angle.
UVR_HOST_DEVICE inline bool crosses(double dn, Vec3d n, Vec3d d) {
    return dn * dn > kGrazing * kGrazing * dot(n, n) * dot(d, d);
}

/// Crossings of the line org + t dir with the triangle a, b, c (canonical order), at most one:
/// t and the sign of dot(dir, n) with n the right-hand normal of a, b, c. Returns the count.
UVR_HOST_DEVICE inline int crossTriangle(Vec3d a, Vec3d b, Vec3d c, Vec3d o, Vec3d d, double* t,
                                         int* sign) {
    Vec3d n;
    double num, den;
    trianglePlane(a, b, c, o, d, n, num, den);
    if (!crosses(den, n, d)) return 0;
    // Barycentrics of the crossing from the edge functions of the line (Moller-Trumbore).
    const Vec3d e1 = b - a, e2 = c - a, pv = cross(d, e2), tv = o - a, qv = cross(tv, e1);
    const double det = dot(e1, pv);  // = -den
    const double u = dot(tv, pv) / det, v = dot(d, qv) / det;
    const double tol = kFaceTolerance;
    if (!(u >= -tol && v >= -tol && u + v <= 1.0 + tol)) return 0;
    t[0] = num / den;
    sign[0] = den > 0.0 ? 1 : -1;
    return 1;
}

/// Crossings of the line org + t dir with the bilinear patch P(u, v) = (1-u)(1-v) q00 + u(1-v)
/// q10 + uv q11 + (1-u)v q01 (corners q[0..3] = q00, q10, q11, q01, canonical order) with (u, v)
/// in [0, 1]^2, at most two: each t and the sign of dot(dir, dP/du x dP/dv). Returns the count.
/// The patch's rulings u = const are lines; the ray meets the ruling at u where both lie in one
/// plane, a quadratic in u (Reshetov 2019, "Cool Patches", Ray Tracing Gems ch. 8), and the
/// ruling's v and t follow from the two lines' nearest points. A trapezoid (u-edges parallel)
/// makes the quadratic linear; a ray within a planar patch's plane crosses it nowhere (the
/// neighbouring faces bound the span), nor does one that touches the patch (a double root).
UVR_HOST_DEVICE inline int crossBilinear(const Vec3d* q, Vec3d o, Vec3d d, double* t, int* sign) {
    const Vec3d q00 = q[0] - o, q10 = q[1] - o, q11 = q[2] - o, q01 = q[3] - o;
    const Vec3d e10 = q10 - q00, e11 = q11 - q10, e00 = q01 - q00;
    // f(u) = det(q00 + u e10, d, e00 + u (e11 - e00)) = a + b u + c u^2.
    const double a = dot(cross(q00, d), e00);
    const double c = dot(cross(e10, q01 - q11), d);
    const double b = dot(cross(q10, d), e11) - a - c;
    double roots[2];
    int nRoots = 0;
    if (c == 0.0) {
        if (b != 0.0) roots[nRoots++] = -a / b;
    } else {
        const double disc = b * b - 4.0 * a * c;
        if (!(disc > 0.0)) return 0;
        const double sq = sqrt(disc);
        const double u1 = -0.5 * (b + (b >= 0.0 ? sq : -sq));  // no cancellation
        if (u1 != 0.0) roots[nRoots++] = a / u1;               // Viete: u1 u2 = a / c
        roots[nRoots++] = u1 / c;
    }
    const double tol = kFaceTolerance;
    int count = 0;
    for (int i = 0; i < nRoots; ++i) {
        const double u = roots[i];
        if (!(u >= -tol && u <= 1.0 + tol)) continue;
        // The ruling at u: pa + v pb; the ray: t d. Their nearest points.
        const Vec3d pa = q00 + e10 * u, pb = e00 + (e11 - e00) * u;
        const Vec3d n = cross(d, pb);
        const double nn = dot(n, n);
        if (!(nn > 0.0)) continue;  // ray parallel to the ruling
        const Vec3d m = cross(n, pa);
        const double v = dot(m, d) / nn;
        if (!(v >= -tol && v <= 1.0 + tol)) continue;
        const double tHit = dot(m, pb) / nn;
        // Normal dP/du x dP/dv at (u, v).
        const Vec3d du = e10 * (1.0 - v) + (q11 - q01) * v;
        const Vec3d normal = cross(du, pb);
        const double dn = dot(d, normal);
        if (!crosses(dn, normal, d)) continue;
        t[count] = tHit;
        sign[count] = dn > 0.0 ? 1 : -1;
        ++count;
    }
    return count;
}

/// clipCell for tetrahedra: the four face planes as half-spaces, as exact::clipTet (each plane
/// from its canonically ordered corners; a plane within kGrazing of the ray counts as parallel).
UVR_HOST_DEVICE inline CellSpan clipTetCell(const Vec3f* x, Vec3d o, Vec3d d, int orientation) {
    CellSpan s;
    for (int f = 0; f < 4; ++f) {
        const std::uint32_t pf = packedFace(CellKind::Tet, f);
        Vec3f a = x[faceCorner(pf, 0)], b = x[faceCorner(pf, 1)], c = x[faceCorner(pf, 2)];
        const int flip = canonicalTriangle(a, b, c) * orientation;
        Vec3d n;
        double num, den;
        trianglePlane(toDouble(a), toDouble(b), toDouble(c), o, d, n, num, den);
        num *= flip, den *= flip;  // n points out
        if (!crosses(den, n, d)) {
            if (num < 0.0) s.tIn = INFINITY, s.tOut = -INFINITY;  // parallel and outside
            continue;
        }
        const double tf = num / den;
        if (den > 0.0) {
            if (tf < s.tOut) s.tOut = tf, s.exitFace = f;
        } else if (tf > s.tIn) {
            s.tIn = tf;
        }
    }
    return s;
}

}  // namespace cellclip

/// Clips the line ray.org + t ray.dir (all t, as exact::clipTet) against the cell of kind k with
/// corners x[0..n-1], in either orientation (the sign of its Jacobian at the parametric centre),
/// in double. Triangular faces are planar; quadrilateral faces are bilinear patches over their
/// corners in packedFace order (the cell's own map on that face). Each crossing of a face enters
/// or leaves by the sign of dir against the face's outward normal there; in the order of t, a
/// span runs from the last of a run of entering crossings to the next leaving one. For a convex
/// cell (every tetrahedron, every affine cell) that is half-space clipping: tIn the last entering
/// crossing (before ray.org when the origin is inside), tOut the first leaving one, exitFace its
/// face. A strongly curved (non-convex) cell that the line crosses twice has two spans: the
/// first one ending after tMin is returned (default: the first along the line), or the last one
/// when none ends after tMin; call again with tMin = tOut for the next. A line that misses (or
/// touches only an edge's tolerance on one side), and a flat or non-finite cell, give tIn =
/// INFINITY, tOut = -INFINITY (tetrahedra: any tIn > tOut, as exact::clipTet). Crossings at a
/// grazing angle (a ray within a face's plane) count as none: the neighbouring faces bound the
/// span.
UVR_HOST_DEVICE inline CellSpan clipCell(CellKind k, const Vec3f* x, const Ray& ray,
                                         double tMin = -INFINITY) {
    using namespace cellclip;
    const int orientation = centreOrientation(k, x);
    CellSpan empty;
    empty.tIn = INFINITY, empty.tOut = -INFINITY;
    if (orientation == 0) return empty;
    const Vec3d o = toDouble(ray.org), d = toDouble(ray.dir);
    if (k == CellKind::Tet) return clipTetCell(x, o, d, orientation);

    // Every face's crossings: t, +1 leaving / -1 entering, face.
    double ts[kMaxCrossings];
    int dirs[kMaxCrossings], faces[kMaxCrossings];
    int count = 0;
    for (int f = 0; f < kindFaces(k); ++f) {
        const std::uint32_t pf = packedFace(k, f);
        double t[2] = {0.0, 0.0};
        int sign[2] = {0, 0}, n;
        if (faceSize(pf) == 3) {
            Vec3f a = x[faceCorner(pf, 0)], b = x[faceCorner(pf, 1)], c = x[faceCorner(pf, 2)];
            const int flip = canonicalTriangle(a, b, c) * orientation;
            n = crossTriangle(toDouble(a), toDouble(b), toDouble(c), o, d, t, sign);
            for (int i = 0; i < n; ++i) sign[i] *= flip;
        } else {
            Vec3f q[4];
            for (int i = 0; i < 4; ++i) q[i] = x[faceCorner(pf, i)];
            const int flip = canonicalQuad(q) * orientation;
            const Vec3d qd[4] = {toDouble(q[0]), toDouble(q[1]), toDouble(q[2]), toDouble(q[3])};
            n = crossBilinear(qd, o, d, t, sign);
            for (int i = 0; i < n; ++i) sign[i] *= flip;
        }
        for (int i = 0; i < n; ++i) {
            // Insertion in the order of t (entering first among equal t).
            int j = count++;
            while (j > 0 && (ts[j - 1] > t[i] || (ts[j - 1] == t[i] && dirs[j - 1] > sign[i]))) {
                ts[j] = ts[j - 1], dirs[j] = dirs[j - 1], faces[j] = faces[j - 1];
                --j;
            }
            ts[j] = t[i], dirs[j] = sign[i], faces[j] = f;
        }
    }

    // Spans: the last of a run of entering crossings to the next leaving one.
    CellSpan span = empty;
    bool open = false;
    double tIn = INFINITY;
    for (int i = 0; i < count; ++i) {
        if (dirs[i] < 0) {
            open = true, tIn = ts[i];
        } else if (open) {
            open = false;
            span.tIn = tIn, span.tOut = ts[i], span.exitFace = faces[i];
            if (span.tOut > tMin) break;
        }
    }
    return span;
}

}  // namespace uvr

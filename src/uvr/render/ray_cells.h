// SPDX-License-Identifier: MIT
#pragma once

// A ray against the mesh's cells, in double: the span of a ray inside one cell (clipAny) and
// the cell a ray is in, or enters next, after a point of it (nextTetAlong, through a BVH of the
// cells). The exact integrator walks cell to cell with them; the sample-based marchers ask where
// a ray that has left a non-convex mesh enters it again (outsideUntil).

#include <cmath>
#include <cstdint>

#include "uvr/accel/bvh.h"
#include "uvr/accel/point_locator.h"
#include "uvr/core/bounds.h"
#include "uvr/core/host_device.h"
#include "uvr/core/ray.h"
#include "uvr/core/vec3d.h"
#include "uvr/mesh/cell_clip.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {
namespace exact {

/// The span [tIn, tOut] of a ray inside a tetrahedron and the face (opposite vertex exitFace)
/// through which it leaves; empty when tIn > tOut. With values: the point field along the ray
/// inside the tetrahedron, v(t) = value0 + valueSlope t, from the barycentric coordinates that
/// the face planes give (each one affine in t), clamped to the tetrahedron's values.
struct TetSpan {
    double tIn = -INFINITY, tOut = INFINITY;
    int exitFace = -1;
    bool hasValue = false;  ///< value0, valueSlope, valueLo, valueHi are set
    double value0 = 0.0, valueSlope = 0.0;
    float valueLo = 0.f, valueHi = 0.f;

    /// The field at parameter t (hasValue).
    UVR_HOST_DEVICE float valueAt(double t) const {
        const float v = static_cast<float>(value0 + valueSlope * t);
        return v < valueLo ? valueLo : (v > valueHi ? valueHi : v);  // NaN stays NaN
    }
};

/// Clips the ray against the four face planes of tetrahedron t (in double; either orientation);
/// withValue: also the point field along the ray (TetSpan::valueAt; not for cell data).
UVR_HOST_DEVICE inline TetSpan clipTet(const TetMeshView& mesh, std::uint32_t t, const Ray& ray,
                                       bool withValue = false) {
    BlockVertex x[4];
    mesh.tetVertices(t, x);
    Vec3d p[4];
    for (int i = 0; i < 4; ++i) p[i] = toDouble(x[i].p);
    const Vec3d o = toDouble(ray.org), d = toDouble(ray.dir);
    TetSpan s;
    bool degenerate = false;
    for (int i = 0; i < 4; ++i) {
        // Face opposite vertex i; its normal points away from vertex i.
        const Vec3d a = p[(i + 1) & 3], b = p[(i + 2) & 3], c = p[(i + 3) & 3];
        // Without fused multiply-adds (crossRounded, dotRounded): a ray lying in a face's plane
        // (a parallel view down an axis of a split grid: the diagonal faces y = z hold rays)
        // has den exactly 0 and its num the same on both cells of the face, as on the CPU.
        // Fused, the GPU's den was a few ulps of |n|, num / den cut the span anywhere, and a
        // quarter of such a ray was lost.
        Vec3d n = crossRounded(b - a, c - a);
        double height = dot(n, p[i] - a);  // vertex i's signed distance (times |n|)
        if (height > 0.0) n = {-n.x, -n.y, -n.z}, height = -height;
        const double num = dotRounded(n, a - o), den = dotRounded(n, d);
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
        if (withValue) {
            // Barycentric i at o + t d: its distance to the face over vertex i's,
            // (t den - num) / height.
            if (!(height < 0.0)) {
                degenerate = true;
                continue;
            }
            const double v = x[i].value;
            s.value0 -= v * num / height;
            s.valueSlope += v * den / height;
        }
    }
    if (withValue && !degenerate) {
        s.hasValue = true;
        s.valueLo = s.valueHi = x[0].value;
        for (int i = 1; i < 4; ++i) {
            const float v = x[i].value;
            s.valueLo = v < s.valueLo ? v : s.valueLo;
            s.valueHi = v > s.valueHi ? v : s.valueHi;
        }
    }
    return s;
}

/// clipCell of native cell t as a TetSpan (without a field).
UVR_HOST_DEVICE inline TetSpan clipNative(const TetMeshView& mesh, std::uint32_t t, const Ray& ray,
                                          double tMin) {
    Vec3f x[kMaxCellCorners];
    mesh.gather(t, x);
    const CellSpan c = clipCell(mesh.kind(t), x, ray, tMin);
    TetSpan s;
    s.tIn = c.tIn, s.tOut = c.tOut, s.exitFace = c.exitFace;
    return s;
}

/// Clips the ray against cell t: clipTet for a tetrahedron; a native cell's faces as planes and
/// bilinear patches (clipCell: of a curved cell the ray crosses twice, the span ending after
/// tMin), without a closed-form field (nativeSegment samples it).
template <bool kNative = true>
UVR_HOST_DEVICE inline TetSpan clipAny(const TetMeshView& mesh, std::uint32_t t, const Ray& ray,
                                       bool withValue = false, double tMin = -INFINITY) {
    if (!kNative || t < mesh.tetCount) return clipTet(mesh, t, ray, withValue);
    return clipNative(mesh, t, ray, tMin);
}

/// The tetrahedron the ray is in just after t (entered last among those it is in, or the
/// nearest ahead): over the BVH's tetrahedra with tOut > t + eps, the one whose max(tIn, t) is
/// smallest (ties: the larger tOut). kNoTet when no tetrahedron lies ahead.
template <bool kNative = true>
UVR_HOST_DEVICE inline std::uint32_t nextTetAlong(const TetMeshView& mesh, const BvhView& bvh,
                                                  const Ray& ray, double t, double eps,
                                                  TetSpan& span, LocateCounters& counters) {
    ++counters.bvhQueries;
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
                const std::uint32_t id = bvh.primIds ? bvh.primIds[node.first + k] : node.first + k;
                const TetSpan s = clipAny<kNative>(mesh, id, ray, false, t + eps);
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

}  // namespace exact

/// Cells boundaryAlong walks at most: a boundary further than this many cells from a sample
/// (cells far smaller than a step s1) is found by bisection instead. Blunt Fin's walks cross
/// 9.5 cells on average (its cells shrink towards the walls); at 16 a third of them gave up.
inline constexpr int kBoundaryWalkCells = 64;

/// Where the ray leaves the mesh after parameter t, t in `cell`, walking cell to cell across
/// shared faces (the exact integrator's step): the parameter of the first face with no
/// neighbour, or tLimit when the ray is still inside there; `cell` ends as the cell left last.
/// NAN when the walk cannot follow the ray: a crossing that does not continue in the
/// neighbour (degenerate, or a tolerance eps too small), no adjacency, or more than
/// kBoundaryWalkCells cells.
template <bool kNative = true>
UVR_HOST_DEVICE inline double boundaryAlong(const TetLocator& loc, std::uint32_t& cell,
                                            const Ray& ray, double t, double tLimit, double eps) {
    if (!loc.neighbors.present() || cell == kNoTet) return NAN;
    for (int i = 0; i < kBoundaryWalkCells; ++i) {
        const exact::TetSpan s = exact::clipAny<kNative>(loc.mesh, cell, ray, false, t - eps);
        if (!(s.tIn <= t + eps && s.tOut > t - eps)) return NAN;  // the ray is not in it at t
        if (s.exitFace < 0) return s.tOut >= tLimit ? tLimit : NAN;
        const std::uint32_t next = loc.neighbors.across<kNative>(loc.mesh, cell, s.exitFace);
        // A face without a neighbour at the limit is the boundary, not the limit: a mesh that
        // fills its bounds ends at the span's start or end, and a clip box around it must not
        // change where (the two differ by rounding).
        if (next == kNoTet && s.tOut <= tLimit + eps) return s.tOut;
        if (s.tOut >= tLimit) return tLimit;
        t = s.tOut > t ? s.tOut : t;
        cell = next;
    }
    return NAN;
}

/// The gap between cells that a ray query (nextTetAlong) takes for rounding, not empty space,
/// on a ray whose span starts at t0 through a mesh of these bounds.
UVR_HOST_DEVICE inline double cellGapEps(const Bounds3f& bounds, float t0) {
    return 1e-6 * (double(bounds.diagonal()) + double(t0));
}

/// For a sample-based marcher whose sample at grid position k (spacing s) lies outside the mesh:
/// a grid position below which every position of the ray lies outside it too, a tenth of s short
/// of where the ray enters the mesh again (a position that close is located as usual; infinity
/// when no cell lies ahead). The marchers take no point location below it, and step from the
/// sample to the last grid position before it. -infinity (nothing known) without a tree.
template <bool kNative = true>
UVR_HOST_DEVICE inline float outsideUntil(const TetMeshView& mesh, const BvhView& tree,
                                          const Ray& ray, float k, float s, double eps,
                                          LocateCounters& counters) {
    if (tree.nodeCount == 0) return -INFINITY;
    exact::TetSpan entry;
    const std::uint32_t next =
        exact::nextTetAlong<kNative>(mesh, tree, ray, double(k) * s, eps, entry, counters);
    return next == kNoTet ? INFINITY : static_cast<float>((entry.tIn - 0.1 * s) / s);
}

/// Where a marcher steps from its outside sample at grid position k: the last position k + n
/// (n whole) below kOutside (outsideUntil), so the step into the mesh is one s as every step
/// outside was.
UVR_HOST_DEVICE inline float lastOutside(float k, float kOutside) {
    return k + ceilf(kOutside - k) - 1.f;
}

}  // namespace uvr

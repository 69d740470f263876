// SPDX-License-Identifier: MIT
#include "uvr/mesh/smooth_gradients.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace uvr {

namespace {

/// Each point's sums in fixed point: integer additions, so a sum is the same whatever order the
/// threads add its terms in (float atomics made two preparations' gradients differ in the last
/// bits, and so two renders of one shaded frame, a pixel apart by 1/255). A term is a multiple of
/// its point's scale (the largest term's magnitude there, found first: a maximum does not depend
/// on order) over 2^kFixedBits: an error of 2^-31 of the largest term, under float rounding. A
/// point takes 2^(63 - kFixedBits) = 2^33 terms before an overflow: more than the cells around
/// it in any mesh of 2^32 cells.
constexpr int kFixedBits = 30;

struct FixedSums {
    std::vector<std::uint32_t> scaleBits;  // per point, 2 floats: the largest |w g_i| and w
    std::vector<std::int64_t> sums;        // per point, 4: w g.x, w g.y, w g.z, w
    explicit FixedSums(std::size_t points) : scaleBits(2 * points, 0), sums(4 * points, 0) {}

    float scale(std::size_t p, int k) const {
        float f;
        std::memcpy(&f, &scaleBits[2 * p + k], 4);
        return f;
    }
    /// Whether a corner's terms count: finite (a huge gradient times a volume may overflow,
    /// and an infinite scale would make every term of the point NaN).
    static bool finite(Vec3f g, float w) {
        return std::isfinite(w * g.x) && std::isfinite(w * g.y) && std::isfinite(w * g.z);
    }
    /// First pass: the scales (non-negative floats order as their bits do).
    void widen(std::uint32_t p, Vec3f g, float w) {
        if (!finite(g, w)) return;
        const float m[2] = {std::max({std::fabs(w * g.x), std::fabs(w * g.y), std::fabs(w * g.z)}),
                            w};
        for (int k = 0; k < 2; ++k) {
            std::uint32_t bits;
            std::memcpy(&bits, &m[k], 4);
            std::atomic_ref<std::uint32_t> at(scaleBits[2 * p + k]);
            std::uint32_t seen = at.load(std::memory_order_relaxed);
            while (seen < bits &&
                   !at.compare_exchange_weak(seen, bits, std::memory_order_relaxed)) {
            }
        }
    }
    /// Second pass: the terms.
    void add(std::uint32_t p, Vec3f g, float w) {
        if (!finite(g, w)) return;
        const float terms[4] = {w * g.x, w * g.y, w * g.z, w};
        for (int i = 0; i < 4; ++i) {
            const float s = scale(p, i < 3 ? 0 : 1);
            if (!(s > 0.f)) continue;
            const auto q = static_cast<std::int64_t>(
                std::llrint(std::ldexp(static_cast<double>(terms[i]) / s, kFixedBits)));
            std::atomic_ref<std::int64_t>(sums[4 * p + i]).fetch_add(q, std::memory_order_relaxed);
        }
    }
    /// The volume-weighted mean gradient at p (0 where no cell gave one).
    Vec3f mean(std::size_t p) const {
        const double w =
            std::ldexp(static_cast<double>(sums[4 * p + 3]), -kFixedBits) * scale(p, 1);
        if (!(w > 0.0)) return Vec3f(0.f);
        const double k = std::ldexp(1.0, -kFixedBits) * scale(p, 0) / w;
        return Vec3f(static_cast<float>(static_cast<double>(sums[4 * p]) * k),
                     static_cast<float>(static_cast<double>(sums[4 * p + 1]) * k),
                     static_cast<float>(static_cast<double>(sums[4 * p + 2]) * k));
    }
};

/// Volume of a native cell: |det J| at its parametric centre times its parametric volume.
float nativeVolume(CellKind k, const Vec3f* x) {
    Vec3f e[kMaxCellCorners];
    const int n = kindCorners(k);
    for (int i = 0; i < n; ++i) e[i] = x[i] - x[0];
    Vec3f at, jr, js, jt;
    cellMap(k, e, cellCentreParametric(k), at, jr, js, jt);
    const float parametric = k == CellKind::Hex ? 1.f : (k == CellKind::Wedge ? 0.5f : 1.f / 3.f);
    return std::fabs(dot(jr, cross(js, jt))) * parametric;
}

/// A position's bits, ordered: equal positions weld (+0 and -0 apart, which no mesh relies on).
struct PositionKey {
    std::uint32_t x, y, z;
    explicit PositionKey(Vec3f p) {
        std::memcpy(&x, &p.x, 4);
        std::memcpy(&y, &p.y, 4);
        std::memcpy(&z, &p.z, 4);
    }
    bool operator<(const PositionKey& o) const {
        return x != o.x ? x < o.x : (y != o.y ? y < o.y : z < o.z);
    }
    bool operator==(const PositionKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

/// Point ids for the block vertices of a mesh that lacks them (read from a prepared cache, which
/// does not store them): vertices at one position are one point. Ids below points.size() are
/// the points at those positions (a native mesh's cache holds its points, which its native cells
/// name); the others are new. Returns the number of ids.
std::uint32_t weldBlockVertices(const TetMesh& mesh, std::vector<std::uint32_t>& ids) {
    const std::size_t points = mesh.points.size(), vertices = mesh.blockVertices.size();
    auto at = [&](std::uint32_t i) {
        return PositionKey(i < points ? mesh.points[i] : mesh.blockVertices[i - points].p);
    };
    std::vector<std::uint32_t> order(points + vertices);
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    // Points first among equal positions, so a group takes a point's id where it has one.
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const PositionKey ka = at(a), kb = at(b);
        return ka < kb || (ka == kb && a < b);
    });
    ids.assign(vertices, 0);
    std::uint32_t next = static_cast<std::uint32_t>(points), group = 0;
    for (std::size_t k = 0; k < order.size(); ++k) {
        const std::uint32_t i = order[k];
        if (k == 0 || !(at(order[k - 1]) == at(i))) group = i < points ? i : next++;
        if (i >= points) ids[i - points] = group;
    }
    return next;
}

}  // namespace

bool hasSmoothGradients(const TetMesh& mesh) {
    if (mesh.association == Association::Cell) return true;
    return mesh.blockGradients.size() == mesh.blockVertices.size() &&
           (!mesh.hasNative() || mesh.pointGradients.size() == mesh.points.size());
}

void computeSmoothGradients(TetMesh& mesh, const FractionFn& progress) {
    mesh.blockGradients.clear();
    mesh.pointGradients.clear();
    ProgressCounter done(progress, 3);
    if (mesh.association == Association::Cell) {
        done.finish();
        return;
    }
    std::vector<std::uint32_t> welded;
    std::size_t points = mesh.points.size();
    if (mesh.blockVertexPoint.size() != mesh.blockVertices.size())
        points = weldBlockVertices(mesh, welded);
    const std::vector<std::uint32_t>& vertexPoint = welded.empty() ? mesh.blockVertexPoint : welded;
    FixedSums fixed(points);
    const TetMeshView view = mesh.view();
    // Calls term(point, gradient, weight) for every cell corner, on threads (twice: the scales,
    // then the sums).
    const auto forEachTerm = [&](auto&& term) {
        const std::int64_t tets = static_cast<std::int64_t>(mesh.tetCount());
#pragma omp parallel for schedule(static, 4096)
        for (std::int64_t t = 0; t < tets; ++t) {
            BlockVertex x[4];
            view.tetVertices(t, x);
            const Vec3f g = tetGradient(x[0].p, x[1].p, x[2].p, x[3].p, x[0].value, x[1].value,
                                        x[2].value, x[3].value);
            const float w = std::fabs(signedVolume6(x[0].p, x[1].p, x[2].p, x[3].p)) / 6.f;
            if (!isFinite(g) || !(w > 0.f)) continue;
            const TetCorners16 c = mesh.tetCorners[t];
            const std::uint32_t base = mesh.blockVertexBase[std::uint64_t(t) >> kTetBlockBits];
            for (int k = 0; k < 4; ++k) term(vertexPoint[base + c.v[k]], g, w);
        }
        const std::int64_t cells = static_cast<std::int64_t>(mesh.cellCount());
#pragma omp parallel for schedule(static, 1024)
        for (std::int64_t c = tets; c < cells; ++c) {
            Vec3f x[kMaxCellCorners];
            float v[kMaxCellCorners];
            std::uint32_t ids[kMaxCellCorners];
            const int n = view.corners(c, ids);
            view.gather(c, x, v);
            const CellKind k = view.kind(c);
            const float w = nativeVolume(k, x);
            if (!(w > 0.f) || !std::isfinite(w)) continue;
            for (int i = 0; i < n; ++i) {
                Vec3f rst = cornerParametric(k, i);
                if (k == CellKind::Pyramid && i == 4) rst = Vec3f(0.5f, 0.5f, 0.5f);  // the apex
                const Vec3f g = cellGradient(k, x, v, rst);
                if (isFinite(g)) term(ids[i], g, w);
            }
        }
        done.add();
    };
    forEachTerm([&](std::uint32_t p, Vec3f g, float w) { fixed.widen(p, g, w); });
    forEachTerm([&](std::uint32_t p, Vec3f g, float w) { fixed.add(p, g, w); });
    std::vector<Vec3f> sums(points);
    const std::int64_t pointCount = static_cast<std::int64_t>(points);
#pragma omp parallel for schedule(static, 65536)
    for (std::int64_t p = 0; p < pointCount; ++p) sums[p] = fixed.mean(p);
    mesh.blockGradients.resize(mesh.blockVertices.size());
    const std::int64_t bv = static_cast<std::int64_t>(mesh.blockVertices.size());
#pragma omp parallel for schedule(static, 65536)
    for (std::int64_t i = 0; i < bv; ++i) mesh.blockGradients[i] = sums[vertexPoint[i]];
    if (mesh.hasNative()) {
        sums.resize(mesh.points.size());  // the welded ids past the points name no native corner
        mesh.pointGradients = std::move(sums);
    }
    done.finish();
}

}  // namespace uvr

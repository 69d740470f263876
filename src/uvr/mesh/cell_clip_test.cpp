// SPDX-License-Identifier: MIT
#include "uvr/mesh/cell_clip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "uvr/mesh/cell_test_support.h"

namespace uvr {
namespace {

using celltest::kindName;
using celltest::kKinds;
using celltest::Rng;
using celltest::uniform;

bool isEmpty(const CellSpan& s) {
    return !(s.tIn <= s.tOut);
}

/// Every span of the ray in the cell, in order (clipCell again from each span's end).
std::vector<CellSpan> allSpans(CellKind k, const Vec3f* x, const Ray& ray) {
    std::vector<CellSpan> spans;
    CellSpan s = clipCell(k, x, ray);
    while (!isEmpty(s) && spans.size() < 8) {
        spans.push_back(s);
        const CellSpan next = clipCell(k, x, ray, s.tOut);
        if (!(next.tOut > s.tOut)) break;
        s = next;
    }
    return spans;
}

/// Whether Newton's method puts p inside the cell, within excess tol of its faces.
bool insideByNewton(CellKind k, const Vec3f* x, Vec3d p, float tol, Vec3f* rstOut = nullptr) {
    Vec3f rst;
    if (!cellParametric(k, x, celltest::toFloat(p), rst)) return false;
    if (rstOut) *rstOut = rst;
    float excess;
    worstFace(k, rst, excess);
    return excess <= tol;
}

Vec3d at(const Ray& ray, double t) {
    return toDouble(ray.org) + toDouble(ray.dir) * t;
}

/// Brute force: marches the ray over [t0, t1] in 20000 steps, each point classified by Newton's
/// method, against clipCell's spans: a point may disagree only within two steps of a span's end.
/// Each span's middle is inside, and its exit point lies on its exitFace. Returns the count of
/// inside points.
int expectSpansMatchBruteForce(CellKind k, const Vec3f* x, const Ray& ray, double t0, double t1) {
    const int steps = 20000;
    const double step = (t1 - t0) / steps;
    const std::vector<CellSpan> spans = allSpans(k, x, ray);
    for (const CellSpan& s : spans) {
        EXPECT_TRUE(std::isfinite(s.tIn) && std::isfinite(s.tOut)) << s.tIn << " " << s.tOut;
        EXPECT_TRUE(insideByNewton(k, x, at(ray, 0.5 * (s.tIn + s.tOut)), 1e-4f))
            << "span [" << s.tIn << ", " << s.tOut << "]";
        Vec3f rst;
        if (insideByNewton(k, x, at(ray, s.tOut), 1e-3f, &rst))
            EXPECT_NEAR(faceExcess(k, rst, s.exitFace), 0.f, 1e-3f) << "exit face " << s.exitFace;
        else
            ADD_FAILURE() << "exit point not on the cell";
    }
    int inside = 0, mismatches = 0;
    for (int i = 0; i <= steps; ++i) {
        const double t = t0 + i * step;
        const bool brute = insideByNewton(k, x, at(ray, t), 1e-6f);
        bool clip = false;
        double nearest = INFINITY;
        for (const CellSpan& s : spans) {
            clip = clip || (s.tIn <= t && t <= s.tOut);
            nearest = std::fmin(nearest, std::fmin(std::fabs(t - s.tIn), std::fabs(t - s.tOut)));
        }
        inside += brute;
        if (brute != clip && nearest > 2 * step) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0) << spans.size() << " spans, first ["
                             << (spans.empty() ? 0 : spans[0].tIn) << ", "
                             << (spans.empty() ? 0 : spans[0].tOut) << "]";
    return inside;
}

/// A random ray through (or near, when near) the cell, with the range [0, t1] that covers it.
Ray randomRay(Rng& rng, CellKind k, const Vec3f* x, bool near, double& t1) {
    const Vec3f target =
        near ? celltest::toFloat(
                   celltest::mapPoint(k, x,
                                      Vec3f(uniform(rng, -0.3f, 1.3f), uniform(rng, -0.3f, 1.3f),
                                            uniform(rng, -0.3f, 1.3f))))
             : celltest::toFloat(celltest::mapPoint(k, x, celltest::randomParametric(rng, k, 0.f)));
    Vec3f dir;
    do dir = Vec3f(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    while (!(length(dir) > 0.1f && length(dir) < 1.f));
    dir = normalize(dir);
    const float reach = 2.f * float(celltest::cellSize(k, x)) + 1.f;
    t1 = 2.0 * reach;
    return {target - dir * reach, dir};
}

/// Half-space clipping by the face planes (each through its first three corners, its normal
/// turned away from the corners' centroid): the oracle for affine cells. Also the next exit
/// after tOut, and the cosines of the ray with the entry and exit faces' normals.
struct HalfSpaceSpan {
    CellSpan span;
    double secondExit = INFINITY, cosIn = 1, cosOut = 1;
};

HalfSpaceSpan halfSpaces(CellKind k, const Vec3f* x, const Ray& ray) {
    Vec3d centroid;
    for (int i = 0; i < kindCorners(k); ++i) centroid = centroid + toDouble(x[i]);
    centroid = centroid * (1.0 / kindCorners(k));
    const Vec3d o = toDouble(ray.org), d = toDouble(ray.dir);
    const double dLength = std::sqrt(dot(d, d));
    HalfSpaceSpan h;
    CellSpan& s = h.span;
    for (int f = 0; f < kindFaces(k); ++f) {
        const std::uint32_t pf = packedFace(k, f);
        const Vec3d a = toDouble(x[faceCorner(pf, 0)]), b = toDouble(x[faceCorner(pf, 1)]),
                    c = toDouble(x[faceCorner(pf, 2)]);
        Vec3d n = normalize(cross(b - a, c - a));
        if (dot(n, centroid - a) > 0) n = n * -1.0;
        const double num = dot(n, a - o), den = dot(n, d);
        const double t = num / den;
        if (den > 0) {
            if (t < s.tOut) {
                h.secondExit = s.tOut, s.tOut = t, s.exitFace = f, h.cosOut = den / dLength;
            } else if (t < h.secondExit) {
                h.secondExit = t;
            }
        } else if (den < 0 && t > s.tIn) {
            s.tIn = t, h.cosIn = -den / dLength;
        }
    }
    return h;
}

TEST(CellClip, AffineCellsMatchHalfSpaceClipping) {
    Rng rng(11);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        int hits = 0, misses = 0;
        for (int it = 0; it < 100; ++it) {
            Vec3f x[kMaxCellCorners];
            celltest::randomCell(rng, k, 0.f, it % 2 == 1, x);
            // The float corners of an affine image are off its planes by their rounding.
            double coord = 1;
            for (int i = 0; i < kindCorners(k); ++i)
                coord = std::fmax(coord, maxComponent(Vec3f(std::fabs(x[i].x), std::fabs(x[i].y),
                                                            std::fabs(x[i].z))));
            const double rounding = 4 * coord * 0x1p-24;
            for (int j = 0; j < 20; ++j) {
                double t1;
                const Ray ray = randomRay(rng, k, x, j % 2 == 1, t1);
                const HalfSpaceSpan ref = halfSpaces(k, x, ray);
                const CellSpan s = clipCell(k, x, ray);
                const double margin = 1e-6 * t1;
                if (ref.span.tIn < ref.span.tOut - margin) {
                    ++hits;
                    EXPECT_NEAR(s.tIn, ref.span.tIn, 1e-12 * t1 + rounding / ref.cosIn)
                        << "cell " << it << " ray " << j;
                    EXPECT_NEAR(s.tOut, ref.span.tOut, 1e-12 * t1 + rounding / ref.cosOut)
                        << "cell " << it << " ray " << j;
                    if (ref.secondExit > ref.span.tOut + margin) {
                        EXPECT_EQ(s.exitFace, ref.span.exitFace);
                    }
                } else if (ref.span.tIn > ref.span.tOut + margin) {
                    ++misses;
                    EXPECT_TRUE(isEmpty(s))
                        << "cell " << it << " ray " << j << ": [" << s.tIn << ", " << s.tOut << "]";
                }
            }
        }
        EXPECT_GT(hits, 1000);
        EXPECT_GT(misses, 100);
    }
}

TEST(CellClip, AffineCellsMatchBruteForce) {
    Rng rng(12);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        int inside = 0;
        for (int it = 0; it < 20; ++it) {
            SCOPED_TRACE(it);
            Vec3f x[kMaxCellCorners];
            celltest::randomCell(rng, k, 0.f, it % 2 == 1, x);
            double t1;
            const Ray ray = randomRay(rng, k, x, it % 3 == 2, t1);
            inside += expectSpansMatchBruteForce(k, x, ray, 0.0, t1);
        }
        EXPECT_GT(inside, 10000) << "too few points inside to test";
    }
}

TEST(CellClip, NonPlanarCellsMatchBruteForce) {
    Rng rng(13);
    for (CellKind k : {CellKind::Pyramid, CellKind::Wedge, CellKind::Hex}) {
        SCOPED_TRACE(kindName(k));
        int inside = 0, cells = 0;
        for (int it = 0; it < 30; ++it) {
            SCOPED_TRACE(it);
            Vec3f x[kMaxCellCorners];
            celltest::randomCell(rng, k, 0.2f, it % 2 == 1, x);
            if (nativeOrientation(k, x) == 0) continue;
            ++cells;
            double t1;
            const Ray ray = randomRay(rng, k, x, it % 3 == 2, t1);
            inside += expectSpansMatchBruteForce(k, x, ray, 0.0, t1);
        }
        EXPECT_GE(cells, 20);
        EXPECT_GT(inside, 20000) << "too few points inside to test";
    }
}

TEST(CellClip, CurvedCellCrossedTwiceGivesTwoSpans) {
    // A unit cube whose top face is a saddle (corners 5 and 7 lowered to z = 0.4): a horizontal
    // line at z = 0.8 along the diagonal leaves through the top and comes back in.
    const Vec3f x[8] = {{0, 0, 0}, {1, 0, 0},    {1, 1, 0}, {0, 1, 0},
                        {0, 0, 1}, {1, 0, 0.4f}, {1, 1, 1}, {0, 1, 0.4f}};
    ASSERT_EQ(nativeOrientation(CellKind::Hex, x), 1);
    const Ray ray{{-0.5f, -0.55f, 0.8f}, normalize(Vec3f(1, 1, 0))};
    const CellSpan first = clipCell(CellKind::Hex, x, ray);
    const CellSpan second = clipCell(CellKind::Hex, x, ray, first.tOut);
    const CellSpan last = clipCell(CellKind::Hex, x, ray, 100.0);
    ASSERT_FALSE(isEmpty(first));
    EXPECT_EQ(first.exitFace, 5);
    ASSERT_FALSE(isEmpty(second));
    EXPECT_GT(second.tIn, first.tOut + 0.5);
    EXPECT_EQ(last.tIn, second.tIn);
    EXPECT_EQ(last.tOut, second.tOut);
    // The line y = x - 0.05 meets the top z = 1 - 0.6 (x + y) + 1.2 x y at z = 0.8 twice, at
    // x = 0.2352 and 0.8148.
    const double s2 = std::sqrt(2.0);
    EXPECT_NEAR(first.tOut, (0.5 + 0.23524) * s2, 1e-4);
    EXPECT_NEAR(second.tIn, (0.5 + 0.81476) * s2, 1e-4);
    EXPECT_GT(expectSpansMatchBruteForce(CellKind::Hex, x, ray, 0.0, 3.0), 1000);
    EXPECT_EQ(allSpans(CellKind::Hex, x, ray).size(), 2u);
}

TEST(CellClip, RaysThatMissAreEmpty) {
    Rng rng(14);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        for (int it = 0; it < 100; ++it) {
            Vec3f x[kMaxCellCorners];
            celltest::randomCell(rng, k, k == CellKind::Tet ? 0.f : 0.2f, it % 2 == 1, x);
            if (nativeOrientation(k, x) == 0) continue;
            // A line past the cell's bounding sphere (centroid, largest corner distance).
            Vec3d c;
            for (int i = 0; i < kindCorners(k); ++i) c = c + toDouble(x[i]);
            c = c * (1.0 / kindCorners(k));
            double radius = 0;
            for (int i = 0; i < kindCorners(k); ++i)
                radius = std::fmax(radius, std::sqrt(dot(toDouble(x[i]) - c, toDouble(x[i]) - c)));
            const Vec3f dir =
                normalize(Vec3f(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)));
            Vec3f side =
                cross(dir, Vec3f(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)));
            side = normalize(side);
            const Vec3f org = celltest::toFloat(c) + side * float(1.01 * radius + 1e-3) -
                              dir * uniform(rng, -5, 5);
            const CellSpan s = clipCell(k, x, Ray{org, dir});
            EXPECT_TRUE(isEmpty(s)) << "cell " << it << ": [" << s.tIn << ", " << s.tOut << "]";
        }
    }
    // Parallel to a face, outside it.
    Vec3f cube[8];
    celltest::referenceCell(CellKind::Hex, cube);
    EXPECT_TRUE(isEmpty(clipCell(CellKind::Hex, cube, Ray{{1.5f, 0.5f, 0.5f}, {0, 1, 0}})));
    EXPECT_TRUE(isEmpty(clipCell(CellKind::Hex, cube, Ray{{0.5f, 0.5f, -0.1f}, {1, 0, 0}})));
}

TEST(CellClip, RaysFromInsideEnterBehindTheOrigin) {
    Rng rng(15);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        for (int it = 0; it < 10; ++it) {
            SCOPED_TRACE(it);
            Vec3f x[kMaxCellCorners];
            celltest::randomCell(rng, k, k == CellKind::Tet ? 0.f : 0.1f, it % 2 == 1, x);
            if (nativeOrientation(k, x) == 0) continue;
            const Vec3f org = celltest::toFloat(
                celltest::mapPoint(k, x, celltest::randomParametric(rng, k, 0.1f)));
            const Vec3f dir =
                normalize(Vec3f(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)));
            const Ray ray{org, dir};
            const CellSpan s = clipCell(k, x, ray);
            EXPECT_LT(s.tIn, 0.0);
            EXPECT_GT(s.tOut, 0.0);
            const double reach = 2 * celltest::cellSize(k, x);
            expectSpansMatchBruteForce(k, x, ray, -reach, reach);
        }
    }
}

TEST(CellClip, RaysAlongFacesAndEdges) {
    Vec3f x[kMaxCellCorners];
    // Within the cube's face x = 0, along its edge x = y = 0, and in that face's plane outside it.
    celltest::referenceCell(CellKind::Hex, x);
    CellSpan s = clipCell(CellKind::Hex, x, Ray{{0, 0.5f, -1}, {0, 0, 1}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 2.0);
    EXPECT_EQ(s.exitFace, 5);
    s = clipCell(CellKind::Hex, x, Ray{{0, 0, -1}, {0, 0, 1}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 2.0);
    EXPECT_EQ(s.exitFace, 5);
    EXPECT_TRUE(isEmpty(clipCell(CellKind::Hex, x, Ray{{0, 1.5f, -1}, {0, 0, 1}})));
    // The same, mirrored (negative orientation).
    for (int i = 0; i < 8; ++i) x[i].x = -x[i].x;
    s = clipCell(CellKind::Hex, x, Ray{{0, 0.5f, 2}, {0, 0, -1}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 2.0);
    EXPECT_EQ(s.exitFace, 4);
    // Within the pyramid's base, and within the wedge's quadrilateral face s = 0 and its
    // triangle t = 0.
    celltest::referenceCell(CellKind::Pyramid, x);
    s = clipCell(CellKind::Pyramid, x, Ray{{-1, 0.5f, 0}, {1, 0, 0}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 2.0);
    EXPECT_EQ(s.exitFace, 2);
    celltest::referenceCell(CellKind::Wedge, x);
    s = clipCell(CellKind::Wedge, x, Ray{{-1, 0, 0.5f}, {1, 0, 0}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 2.0);
    EXPECT_EQ(s.exitFace, 3);
    s = clipCell(CellKind::Wedge, x, Ray{{0.25f, -1, 0}, {0, 1, 0}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 1.75);
    EXPECT_EQ(s.exitFace, 3);
    // A tetrahedron's face y = 0.
    celltest::referenceCell(CellKind::Tet, x);
    s = clipCell(CellKind::Tet, x, Ray{{-1, 0, 0.25f}, {1, 0, 0}});
    EXPECT_DOUBLE_EQ(s.tIn, 1.0);
    EXPECT_DOUBLE_EQ(s.tOut, 1.75);
    EXPECT_EQ(s.exitFace, 0);
}

TEST(CellClip, SharedNonPlanarFaceIsWatertight) {
    // Hexahedron a (VTK order) and b beyond its face r = 1 (corners 1, 2, 6, 5), b's corners
    // numbered in several ways (two with a negative map).
    const int orders[4][8] = {{0, 1, 2, 3, 4, 5, 6, 7},
                              {1, 2, 3, 0, 5, 6, 7, 4},
                              {4, 5, 6, 7, 0, 1, 2, 3},
                              {1, 0, 3, 2, 5, 4, 7, 6}};
    Rng rng(16);
    int compared = 0;
    for (int it = 0; it < 200; ++it) {
        Vec3f a[8], bVtk[8], b[8];
        celltest::referenceCell(CellKind::Hex, a);
        celltest::jitter(rng, a, 8, 0.2f);
        for (int i = 0; i < 8; ++i) bVtk[i] = a[i] + Vec3f(1, 0, 0);
        celltest::jitter(rng, bVtk, 8, 0.2f);
        bVtk[0] = a[1], bVtk[3] = a[2], bVtk[7] = a[6], bVtk[4] = a[5];
        const celltest::Affine m = celltest::randomAffine(rng, it % 2 == 1);
        for (int i = 0; i < 8; ++i) a[i] = m.apply(a[i]), bVtk[i] = m.apply(bVtk[i]);
        for (int i = 0; i < 8; ++i) b[i] = bVtk[orders[it % 4][i]];
        if (nativeOrientation(CellKind::Hex, a) == 0 || nativeOrientation(CellKind::Hex, b) == 0)
            continue;
        for (int j = 0; j < 10; ++j) {
            const Vec3f pa = celltest::toFloat(
                celltest::mapPoint(CellKind::Hex, a,
                                   Vec3f(uniform(rng, 0.3f, 0.7f), uniform(rng, 0.3f, 0.7f),
                                         uniform(rng, 0.3f, 0.7f))));
            const Vec3f pb = celltest::toFloat(
                celltest::mapPoint(CellKind::Hex, bVtk,
                                   Vec3f(uniform(rng, 0.3f, 0.7f), uniform(rng, 0.3f, 0.7f),
                                         uniform(rng, 0.3f, 0.7f))));
            const Vec3f dir = normalize(pb - pa);
            const Ray ray{pa - dir * uniform(rng, 0.f, 10.f), dir};
            const CellSpan sa = clipCell(CellKind::Hex, a, ray),
                           sb = clipCell(CellKind::Hex, b, ray);
            ASSERT_FALSE(isEmpty(sa));
            ASSERT_FALSE(isEmpty(sb));
            if (sa.exitFace != 1) continue;  // left a through another face
            ++compared;
            EXPECT_NEAR(sb.tIn, sa.tOut, 1e-9 * std::fabs(sa.tOut))
                << "cell " << it << " ray " << j;
            EXPECT_EQ(sb.tIn, sa.tOut) << "cell " << it << " ray " << j << ": not bit for bit";
        }
    }
    EXPECT_GT(compared, 1000);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/mesh/cell_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "uvr/mesh/cell_test_support.h"

namespace uvr {
namespace {

using celltest::kindName;
using celltest::kKinds;
using celltest::Rng;
using celltest::uniform;

TEST(CellMath, ShapeFunctionsArePartitionOfUnityAndKronecker) {
    Rng rng(1);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        const int n = kindCorners(k);
        float w[kMaxCellCorners];
        for (int j = 0; j < n; ++j) {
            const Vec3f c = cornerParametric(k, j);
            shapeFunctions(k, c.x, c.y, c.z, w);
            for (int i = 0; i < n; ++i) EXPECT_EQ(w[i], i == j ? 1.f : 0.f) << i << " at " << j;
        }
        for (int it = 0; it < 200; ++it) {
            const Vec3f p(uniform(rng, -0.5f, 1.5f), uniform(rng, -0.5f, 1.5f),
                          uniform(rng, -0.5f, 1.5f));
            shapeFunctions(k, p.x, p.y, p.z, w);
            double sum = 0;
            for (int i = 0; i < n; ++i) sum += w[i];
            EXPECT_NEAR(sum, 1.0, 1e-6);
        }
    }
}

TEST(CellMath, ShapeFunctionDerivativesMatchCentralDifferences) {
    Rng rng(2);
    const float h = 1e-2f;
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        const int n = kindCorners(k);
        for (int it = 0; it < 100; ++it) {
            const Vec3f p(uniform(rng, -0.2f, 1.2f), uniform(rng, -0.2f, 1.2f),
                          uniform(rng, -0.2f, 1.2f));
            float w[kMaxCellCorners], d[3][kMaxCellCorners];
            shapeFunctions(k, p.x, p.y, p.z, w, d[0], d[1], d[2]);
            for (int axis = 0; axis < 3; ++axis) {
                Vec3f lo = p, hi = p;
                lo[axis] -= h, hi[axis] += h;
                float wl[kMaxCellCorners], wh[kMaxCellCorners];
                shapeFunctions(k, lo.x, lo.y, lo.z, wl);
                shapeFunctions(k, hi.x, hi.y, hi.z, wh);
                for (int i = 0; i < n; ++i)
                    EXPECT_NEAR(d[axis][i], (wh[i] - wl[i]) / (hi[axis] - lo[axis]), 1e-4)
                        << "corner " << i << " axis " << axis;
            }
        }
    }
}

/// Random cells of kind k for the round trips: affine images (every fourth mirrored), and every
/// other one jittered (hexahedra by up to 0.2 of the unit cube: non-planar faces).
void testCell(Rng& rng, CellKind k, int it, Vec3f* x) {
    const float amp = it % 2 == 0 ? 0.f : (k == CellKind::Hex ? 0.2f : 0.1f);
    celltest::randomCell(rng, k, amp, it % 4 == 1 || it % 4 == 2, x);
}

TEST(CellMath, ParametricRoundTripsOnDistortedCells) {
    Rng rng(3);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        int tested = 0;
        for (int it = 0; it < 200; ++it) {
            Vec3f x[kMaxCellCorners];
            testCell(rng, k, it, x);
            if (nativeOrientation(k, x) == 0) continue;
            ++tested;
            for (int j = 0; j < 20; ++j) {
                const Vec3f rst = celltest::randomParametric(rng, k, 0.f);
                const Vec3f p = celltest::toFloat(celltest::mapPoint(k, x, rst));
                Vec3f back;
                ASSERT_TRUE(cellParametric(k, x, p, back)) << "cell " << it;
                EXPECT_NEAR(back.x, rst.x, 1e-4) << "cell " << it;
                EXPECT_NEAR(back.y, rst.y, 1e-4) << "cell " << it;
                EXPECT_NEAR(back.z, rst.z, 1e-4) << "cell " << it;
                float excess;
                worstFace(k, back, excess);
                EXPECT_LE(excess, 1e-4f);
            }
        }
        EXPECT_GE(tested, 190);  // jittered cells rarely fold
    }
}

TEST(CellMath, OutsidePointsNameTheirFace) {
    struct Case {
        CellKind k;
        Vec3f rst;
        int face;
        float excess;
    };
    const Case cases[] = {
        {CellKind::Hex, {-0.3f, 0.5f, 0.5f}, 0, 0.3f},
        {CellKind::Hex, {1.3f, 0.4f, 0.5f}, 1, 0.3f},
        {CellKind::Hex, {0.5f, -0.2f, 0.5f}, 2, 0.2f},
        {CellKind::Hex, {0.5f, 1.1f, 0.5f}, 3, 0.1f},
        {CellKind::Hex, {0.5f, 0.6f, -0.4f}, 4, 0.4f},
        {CellKind::Hex, {0.5f, 0.5f, 1.4f}, 5, 0.4f},
        {CellKind::Wedge, {0.2f, 0.2f, -0.3f}, 0, 0.3f},
        {CellKind::Wedge, {0.2f, 0.2f, 1.2f}, 1, 0.2f},
        {CellKind::Wedge, {0.3f, -0.2f, 0.5f}, 2, 0.2f},
        {CellKind::Wedge, {0.6f, 0.6f, 0.5f}, 3, 0.2f},
        {CellKind::Wedge, {-0.3f, 0.3f, 0.5f}, 4, 0.3f},
        {CellKind::Pyramid, {0.5f, 0.5f, -0.2f}, 0, 0.2f},
        // (A pyramid's sides count times 1 - t.)
        {CellKind::Pyramid, {0.5f, -0.3f, 0.3f}, 1, 0.21f},
        {CellKind::Pyramid, {1.2f, 0.5f, 0.3f}, 2, 0.14f},
        {CellKind::Pyramid, {0.5f, 1.3f, 0.3f}, 3, 0.21f},
        {CellKind::Pyramid, {-0.2f, 0.5f, 0.3f}, 4, 0.14f},
        // Beyond a pyramid's apex, where its map mirrors it: outside the side r = 1.
        {CellKind::Pyramid, {0.3f, 0.5f, 1.5f}, 2, 0.35f},
        {CellKind::Tet, {0.5f, 0.5f, 0.5f}, 0, 0.5f},
        {CellKind::Tet, {-0.2f, 0.3f, 0.3f}, 1, 0.2f},
        {CellKind::Tet, {0.3f, -0.1f, 0.3f}, 2, 0.1f},
        {CellKind::Tet, {0.3f, 0.3f, -0.3f}, 3, 0.3f},
    };
    Rng rng(4);
    for (const Case& c : cases) {
        SCOPED_TRACE(::testing::Message() << kindName(c.k) << " face " << c.face);
        // The reference cell, then affine images of it (Newton is exact there).
        for (int it = 0; it < 5; ++it) {
            Vec3f x[kMaxCellCorners];
            celltest::referenceCell(c.k, x);
            if (it > 0) {
                const celltest::Affine a = celltest::randomAffine(rng, it % 2 == 0);
                for (int i = 0; i < kindCorners(c.k); ++i) x[i] = a.apply(x[i]);
            }
            const Vec3f p = celltest::toFloat(celltest::mapPoint(c.k, x, c.rst));
            Vec3f rst;
            ASSERT_TRUE(cellParametric(c.k, x, p, rst));
            float excess = 0.f;
            EXPECT_EQ(worstFace(c.k, rst, excess), c.face);
            EXPECT_NEAR(excess, c.excess, 1e-4);
        }
    }
}

TEST(CellMath, ParametricFailsGracefullyOnCollapsedCells) {
    Vec3f x[8];
    Vec3f rst;
    // All corners at one point.
    for (Vec3f& c : x) c = Vec3f(1.f, 2.f, 3.f);
    EXPECT_FALSE(cellParametric(CellKind::Hex, x, Vec3f(1.5f, 2.f, 3.f), rst));
    // Flat: the top face on the bottom one, a point off their plane.
    celltest::referenceCell(CellKind::Hex, x);
    for (int i = 4; i < 8; ++i) x[i].z = 0.f;
    EXPECT_FALSE(cellParametric(CellKind::Hex, x, Vec3f(0.5f, 0.5f, 0.5f), rst));
    EXPECT_FALSE(cellParametric(CellKind::Wedge, x, Vec3f(0.2f, 0.2f, 0.5f), rst));
    // A NaN corner.
    celltest::referenceCell(CellKind::Hex, x);
    x[6].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(cellParametric(CellKind::Hex, x, Vec3f(0.5f, 0.5f, 0.5f), rst));
}

TEST(CellMath, LinearFieldsAreReproducedOnDistortedHexahedra) {
    Rng rng(5);
    for (int it = 0; it < 100; ++it) {
        SCOPED_TRACE(it);
        Vec3f x[8];
        celltest::randomCell(rng, CellKind::Hex, 0.2f, it % 2 == 1, x);
        if (nativeOrientation(CellKind::Hex, x) == 0) continue;
        const double a = uniform(rng, -2, 2);
        const Vec3d b = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
        const auto field = [&](Vec3d p) { return a + dot(b, p); };
        float v[8];
        double scale = std::fabs(a);
        for (int i = 0; i < 8; ++i) {
            v[i] = float(field(toDouble(x[i])));
            scale = std::fmax(scale, std::fabs(v[i]));
        }
        for (int j = 0; j < 20; ++j) {
            // A random interior point, located by Newton's method.
            const Vec3f p = celltest::toFloat(celltest::mapPoint(
                CellKind::Hex, x, celltest::randomParametric(rng, CellKind::Hex, 0.f)));
            Vec3f rst;
            ASSERT_TRUE(cellParametric(CellKind::Hex, x, p, rst));
            EXPECT_NEAR(celltest::interpolate(CellKind::Hex, v, rst), field(toDouble(p)),
                        1e-4 * scale);
        }
    }
}

TEST(CellMath, TrilinearFieldIsReproducedOnBoxes) {
    Rng rng(6);
    for (int it = 0; it < 50; ++it) {
        SCOPED_TRACE(it);
        const Vec3f lo(uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -3, 3));
        const Vec3f size(uniform(rng, 0.1f, 4), uniform(rng, 0.1f, 4), uniform(rng, 0.1f, 4));
        Vec3f x[8];
        float v[8];
        double scale = 0;
        for (int i = 0; i < 8; ++i) {
            x[i] = lo + cornerParametric(CellKind::Hex, i) * size;
            v[i] = x[i].x * x[i].y * x[i].z;
            scale = std::fmax(scale, std::fabs(v[i]));
        }
        for (int j = 0; j < 20; ++j) {
            const Vec3f p =
                lo + Vec3f(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1)) * size;
            Vec3f rst;
            ASSERT_TRUE(cellParametric(CellKind::Hex, x, p, rst));
            EXPECT_NEAR(celltest::interpolate(CellKind::Hex, v, rst), double(p.x) * p.y * p.z,
                        1e-4 * scale);
        }
    }
}

TEST(CellMath, GradientMatchesFiniteDifferences) {
    Rng rng(7);
    for (CellKind k : kKinds) {
        SCOPED_TRACE(kindName(k));
        for (int it = 0; it < 40; ++it) {
            Vec3f x[kMaxCellCorners];
            testCell(rng, k, it, x);
            if (nativeOrientation(k, x) == 0) continue;
            float v[kMaxCellCorners];
            float vmax = 0.f;
            for (int i = 0; i < kindCorners(k); ++i) {
                v[i] = uniform(rng, -1, 1);
                vmax = std::fmax(vmax, std::fabs(v[i]));
            }
            const float size = float(celltest::cellSize(k, x));
            const Vec3f rst0 = celltest::randomParametric(rng, k, 0.1f);
            const Vec3f p = celltest::toFloat(celltest::mapPoint(k, x, rst0));
            Vec3f rst;
            ASSERT_TRUE(cellParametric(k, x, p, rst));
            const Vec3f g = cellGradient(k, x, v, rst);
            // Central differences of the interpolated field in x, y and z.
            const float h = 3e-3f * size;
            for (int axis = 0; axis < 3; ++axis) {
                Vec3f lo = p, hi = p, rlo, rhi;
                lo[axis] -= h, hi[axis] += h;
                ASSERT_TRUE(cellParametric(k, x, lo, rlo));
                ASSERT_TRUE(cellParametric(k, x, hi, rhi));
                const double fd =
                    (celltest::interpolate(k, v, rhi) - celltest::interpolate(k, v, rlo)) /
                    (double(hi[axis]) - lo[axis]);
                EXPECT_NEAR(g[axis], fd, 2e-3 * vmax / size) << "cell " << it << " axis " << axis;
            }
        }
    }
}

TEST(CellMath, NativeOrientation) {
    // VTK's own cells (vtkCellTypeSource, one block): positive in VTK's sense.
    const Vec3f hex[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                          {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    const Vec3f pyramid[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 0.5f}};
    const Vec3f tet[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 1}};
    // VTK's wedge has its triangle 0, 1, 2's right-hand normal pointing away from 3, 4, 5; with the
    // triangle 0, 1, 2 in the r, s plane of the parametric map, that map's Jacobian is negative.
    const Vec3f wedge[6] = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 1}};
    EXPECT_EQ(nativeOrientation(CellKind::Hex, hex), 1);
    EXPECT_EQ(nativeOrientation(CellKind::Pyramid, pyramid), 1);
    EXPECT_EQ(nativeOrientation(CellKind::Tet, tet), 1);
    EXPECT_EQ(nativeOrientation(CellKind::Wedge, wedge), -1);
    Vec3f x[8];
    celltest::referenceCell(CellKind::Wedge, x);
    EXPECT_EQ(nativeOrientation(CellKind::Wedge, x), 1);
    // Mirrored.
    for (int i = 0; i < 8; ++i) x[i] = Vec3f(-hex[i].x, hex[i].y, hex[i].z);
    EXPECT_EQ(nativeOrientation(CellKind::Hex, x), -1);
    // Twisted: two top corners swapped.
    for (int i = 0; i < 8; ++i) x[i] = hex[i];
    x[6] = hex[7], x[7] = hex[6];
    EXPECT_EQ(nativeOrientation(CellKind::Hex, x), 0);
    // Collapsed: the top face on the bottom one.
    for (int i = 0; i < 8; ++i) x[i] = Vec3f(hex[i].x, hex[i].y, 0.f);
    EXPECT_EQ(nativeOrientation(CellKind::Hex, x), 0);
    // A NaN corner.
    for (int i = 0; i < 8; ++i) x[i] = hex[i];
    x[3].z = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(nativeOrientation(CellKind::Hex, x), 0);
}

}  // namespace
}  // namespace uvr

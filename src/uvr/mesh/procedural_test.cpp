// SPDX-License-Identifier: MIT
#include "uvr/mesh/procedural.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/mesh/cell_math.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/mesh/validate.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

constexpr ProceduralShape kShapes[] = {ProceduralShape::Box, ProceduralShape::Shell,
                                       ProceduralShape::Graded};

ProceduralSpec makeSpec(ProceduralShape shape, std::uint64_t target, std::uint64_t seed = 1) {
    ProceduralSpec spec;
    spec.shape = shape;
    spec.targetCells = target;
    spec.seed = seed;
    return spec;
}

/// True when p lies in tetrahedron c (barycentric coordinates all >= -eps).
bool insideTet(const Mesh& m, std::uint64_t c, Vec3f p, double eps = 1e-9) {
    auto ids = m.cell(c);
    const Vec3f v[4] = {m.points[ids[0]], m.points[ids[1]], m.points[ids[2]], m.points[ids[3]]};
    auto vol = [](Vec3f a, Vec3f b, Vec3f cc, Vec3f d) {
        const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
        const double vx = cc.x - a.x, vy = cc.y - a.y, vz = cc.z - a.z;
        const double wx = d.x - a.x, wy = d.y - a.y, wz = d.z - a.z;
        return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
    };
    const double total = vol(v[0], v[1], v[2], v[3]);
    const double b0 = vol(p, v[1], v[2], v[3]) / total, b1 = vol(v[0], p, v[2], v[3]) / total,
                 b2 = vol(v[0], v[1], p, v[3]) / total, b3 = vol(v[0], v[1], v[2], p) / total;
    return b0 >= -eps && b1 >= -eps && b2 >= -eps && b3 >= -eps;
}

bool insideAnyTet(const Mesh& m, Vec3f p) {
    for (std::uint64_t c = 0; c < m.cellCount(); ++c)
        if (insideTet(m, c, p)) return true;
    return false;
}

/// Distance of p from the centre circle of the Shell's tube.
double tubeDistance(Vec3f p) {
    const double rho = std::hypot(p.x, p.y) - kShellMajorRadius;
    return std::hypot(rho, static_cast<double>(p.z));
}

TEST(Procedural, SameSpecGivesIdenticalMeshDifferentSeedDiffers) {
    for (ProceduralShape shape : kShapes) {
        SCOPED_TRACE(proceduralShapeName(shape));
        const Mesh a = generateMesh(makeSpec(shape, 20000, 7));
        const Mesh b = generateMesh(makeSpec(shape, 20000, 7));
        ASSERT_EQ(a.points.size(), b.points.size());
        EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * 12));
        EXPECT_EQ(a.cellIndices, b.cellIndices);
        EXPECT_EQ(a.cellOffsets, b.cellOffsets);
        EXPECT_EQ(a.cellTypes, b.cellTypes);
        ASSERT_EQ(a.fields.size(), b.fields.size());
        for (size_t f = 0; f < a.fields.size(); ++f) {
            EXPECT_EQ(a.fields[f].name, b.fields[f].name);
            EXPECT_EQ(0, std::memcmp(a.fields[f].values.data(), b.fields[f].values.data(),
                                     a.fields[f].values.size() * 4));
        }
        const Mesh c = generateMesh(makeSpec(shape, 20000, 8));
        ASSERT_EQ(a.points.size(), c.points.size());
        size_t moved = 0;
        for (size_t i = 0; i < a.points.size(); ++i) moved += !(a.points[i] == c.points[i]);
        EXPECT_GT(moved, a.points.size() / 2) << "a different seed must move most points";
    }
}

TEST(Procedural, EveryTetrahedronIsPositivelyOriented) {
    for (ProceduralShape shape : kShapes) {
        for (std::uint64_t target : {1ull, 500ull, 6000ull, 80000ull}) {
            for (float jitter : {0.f, 0.2f, kMaxProceduralJitter}) {
                for (std::uint64_t seed : {1ull, 99ull}) {
                    ProceduralSpec spec = makeSpec(shape, target, seed);
                    spec.jitter = jitter;
                    spec.fields = {};
                    const Mesh m = generateMesh(spec);
                    ASSERT_GT(m.cellCount(), 0u);
                    double minVolume = 1e30;
                    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
                        ASSERT_EQ(m.cellTypes[c], CellType::Tetra);
                        minVolume = std::min(minVolume, testing::tetVolume(m, c));
                    }
                    EXPECT_GT(minVolume, 0.0) << proceduralShapeName(shape) << " target " << target
                                              << " jitter " << jitter << " seed " << seed;
                }
            }
        }
    }
}

TEST(Procedural, TotalVolumeMatchesTheDomain) {
    // The cube shapes partition [-1,1]^3 exactly; the Shell approximates the hollow torus volume
    // 2 pi^2 R (r1^2 - r0^2) from inside (its faces are chords).
    for (ProceduralShape shape : {ProceduralShape::Box, ProceduralShape::Graded}) {
        const Mesh m = generateMesh(makeSpec(shape, 30000));
        double total = 0;
        for (std::uint64_t c = 0; c < m.cellCount(); ++c) total += testing::tetVolume(m, c);
        EXPECT_NEAR(total, 8.0, 1e-4) << proceduralShapeName(shape);
        const Bounds3f b = m.bounds();
        EXPECT_EQ(b.lo, Vec3f(-1.f)) << proceduralShapeName(shape);
        EXPECT_EQ(b.hi, Vec3f(1.f)) << proceduralShapeName(shape);
    }
    const Mesh shell = generateMesh(makeSpec(ProceduralShape::Shell, 200000));
    double total = 0;
    for (std::uint64_t c = 0; c < shell.cellCount(); ++c) total += testing::tetVolume(shell, c);
    const double exact =
        2.0 * std::numbers::pi * std::numbers::pi * kShellMajorRadius *
        (kShellOuterRadius * kShellOuterRadius - kShellInnerRadius * kShellInnerRadius);
    EXPECT_LT(total, exact);
    EXPECT_GT(total, 0.97 * exact);
    const Bounds3f b = shell.bounds();
    EXPECT_GE(b.lo.x, -1.f);
    EXPECT_LE(b.hi.x, 1.f);
    EXPECT_GE(b.lo.z, -1.f);
    EXPECT_LE(b.hi.z, 1.f);
}

TEST(Procedural, InteriorFacesAreSharedByExactlyTwoTetsOthersLieOnTheBoundary) {
    for (ProceduralShape shape : kShapes) {
        SCOPED_TRACE(proceduralShapeName(shape));
        ProceduralSpec spec = makeSpec(shape, 3000, 5);
        spec.fields = {};
        const Mesh m = generateMesh(spec);
        std::map<std::array<std::uint32_t, 3>, int> faces;
        for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
            auto ids = m.cell(c);
            for (int skip = 0; skip < 4; ++skip) {
                std::array<std::uint32_t, 3> f{};
                int n = 0;
                for (int v = 0; v < 4; ++v)
                    if (v != skip) f[n++] = ids[v];
                std::sort(f.begin(), f.end());
                ++faces[f];
            }
        }
        size_t interior = 0, boundary = 0;
        for (const auto& [face, count] : faces) {
            ASSERT_LE(count, 2) << "face shared by " << count << " tetrahedra";
            if (count == 2) {
                ++interior;
                continue;
            }
            ++boundary;
            const Vec3f a = m.points[face[0]], b = m.points[face[1]], c = m.points[face[2]];
            if (shape == ProceduralShape::Shell) {
                // A boundary face lies on the inner or the outer wall of the tube.
                const double ra = tubeDistance(a), rb = tubeDistance(b), rc = tubeDistance(c);
                const bool inner = std::abs(ra - kShellInnerRadius) < 1e-5 &&
                                   std::abs(rb - kShellInnerRadius) < 1e-5 &&
                                   std::abs(rc - kShellInnerRadius) < 1e-5;
                const bool outer = std::abs(ra - kShellOuterRadius) < 1e-5 &&
                                   std::abs(rb - kShellOuterRadius) < 1e-5 &&
                                   std::abs(rc - kShellOuterRadius) < 1e-5;
                EXPECT_TRUE(inner || outer)
                    << "boundary face off the walls: radii " << ra << ", " << rb << ", " << rc;
            } else {
                bool onCubeFace = false;
                for (int axis = 0; axis < 3; ++axis)
                    for (float side : {-1.f, 1.f})
                        onCubeFace |= a[axis] == side && b[axis] == side && c[axis] == side;
                EXPECT_TRUE(onCubeFace) << "boundary face inside the cube";
            }
        }
        EXPECT_GT(interior, boundary);
        // Euler-style sanity: 4 faces per tet = 2 per interior face + 1 per boundary face.
        EXPECT_EQ(4 * m.cellCount(), 2 * interior + boundary);
    }
}

TEST(Procedural, LinearFieldEqualsTheFormulaAtEveryPoint) {
    for (ProceduralShape shape : kShapes) {
        ProceduralSpec spec = makeSpec(shape, 20000);
        spec.fields = {ProceduralField::Linear, ProceduralField::Constant};
        const Mesh m = generateMesh(spec);
        const Field* linear = m.findField("linear", Association::Point);
        const Field* constant = m.findField("constant", Association::Point);
        ASSERT_NE(linear, nullptr);
        ASSERT_NE(constant, nullptr);
        ASSERT_EQ(linear->values.size(), m.pointCount());
        for (size_t i = 0; i < m.points.size(); ++i) {
            const Vec3f p = m.points[i];
            ASSERT_NEAR(linear->values[i], p.x + 2.0 * p.y - p.z, 1e-5) << "point " << i;
            ASSERT_EQ(constant->values[i], 1.f) << "point " << i;
        }
    }
}

TEST(Procedural, FieldsFollowTheSpecOrderAndStayInRange) {
    const ProceduralSpec spec = makeSpec(ProceduralShape::Box, 50000);
    const Mesh m = generateMesh(spec);
    ASSERT_EQ(m.fields.size(), spec.fields.size());
    for (size_t f = 0; f < spec.fields.size(); ++f) {
        EXPECT_EQ(m.fields[f].name, proceduralFieldName(spec.fields[f]));
        EXPECT_EQ(m.fields[f].association, Association::Point);
        EXPECT_EQ(m.fields[f].components, 1);
    }
    for (const char* name : {"jet", "marschner_lobb"}) {
        const Field* field = m.findField(name, Association::Point);
        ASSERT_NE(field, nullptr);
        const auto [lo, hi] = std::minmax_element(field->values.begin(), field->values.end());
        EXPECT_GE(*lo, 0.f) << name;
        EXPECT_LE(*hi, 1.f) << name;
        EXPECT_GT(*hi - *lo, 0.5f) << name << " should span most of [0, 1]";
    }
    // The jet is strong on its axis near the nozzle and faint far from it.
    EXPECT_GT(proceduralFieldValue(ProceduralField::Jet, {0.f, -0.95f, 0.f}), 0.6f);
    EXPECT_LT(proceduralFieldValue(ProceduralField::Jet, {0.9f, -0.95f, 0.9f}), 0.01f);
    // Marschner-Lobb at the origin: (1 - 0 + 0.25 (1 + cos(12 pi))) / 2.5 = 0.6.
    EXPECT_NEAR(proceduralFieldValue(ProceduralField::MarschnerLobb, {0.f, 0.f, 0.f}), 0.6f, 1e-6);
    // At z = 1, r = 1: (1 - 1 + 0.25 (1 + cos(12 pi cos(pi/2)))) / 2.5 = 0.2.
    EXPECT_NEAR(proceduralFieldValue(ProceduralField::MarschnerLobb, {1.f, 0.f, 1.f}), 0.2f, 1e-6);
}

TEST(Procedural, CellCountIsWithinTwiceTheTarget) {
    for (ProceduralShape shape : kShapes) {
        for (std::uint64_t target : {1000ull, 7777ull, 100000ull, 1000000ull}) {
            ProceduralSpec spec = makeSpec(shape, target);
            spec.fields = {};
            const Mesh m = generateMesh(spec);
            const double ratio = static_cast<double>(m.cellCount()) / target;
            EXPECT_GE(ratio, 0.5) << proceduralShapeName(shape) << " target " << target;
            EXPECT_LE(ratio, 2.0) << proceduralShapeName(shape) << " target " << target;
            EXPECT_EQ(m.cellOffsets.size(), m.cellCount() + 1);
            EXPECT_EQ(m.cellOffsets.back(), m.cellIndices.size());
        }
    }
}

TEST(Procedural, ShellIsHollowAndHasAHole) {
    ProceduralSpec spec = makeSpec(ProceduralShape::Shell, 30000);
    spec.fields = {};
    const Mesh m = generateMesh(spec);
    EXPECT_FALSE(insideAnyTet(m, {0.f, 0.f, 0.f})) << "the centre of the torus hole";
    EXPECT_FALSE(insideAnyTet(m, {0.2f, -0.1f, 0.05f})) << "elsewhere in the torus hole";
    EXPECT_FALSE(insideAnyTet(m, {kShellMajorRadius, 0.f, 0.f})) << "the tube's empty core";
    EXPECT_FALSE(insideAnyTet(m, {0.f, -kShellMajorRadius + 0.05f, 0.03f}))
        << "the tube's empty core";
    EXPECT_TRUE(insideAnyTet(m, {kShellMajorRadius + 0.21f, 0.013f, 0.011f})) << "in the wall";
    EXPECT_TRUE(insideAnyTet(m, {0.017f, -kShellMajorRadius, 0.2f})) << "in the wall";
    EXPECT_FALSE(insideAnyTet(m, {0.f, 0.f, 0.5f})) << "above the torus";
}

TEST(Procedural, GradedEdgeRatioIsAboutOneHundred) {
    ProceduralSpec spec = makeSpec(ProceduralShape::Graded, 50000);
    spec.jitter = 0.f;  // edge lengths are then exactly those of the graded grid
    spec.fields = {};
    const Mesh m = generateMesh(spec);
    double shortest = 1e30, longest = 0;
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        auto ids = m.cell(c);
        for (int a = 0; a < 4; ++a) {
            for (int b = a + 1; b < 4; ++b) {
                const Vec3f d = m.points[ids[a]] - m.points[ids[b]];
                const double len =
                    std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
                shortest = std::min(shortest, len);
                longest = std::max(longest, len);
            }
        }
    }
    EXPECT_GE(longest / shortest, 50.0);
    EXPECT_LE(longest / shortest, 200.0);
}

TEST(Procedural, BoxBoundaryPointsStayOnTheBoundary) {
    const Mesh m = generateMesh(makeSpec(ProceduralShape::Box, 6 * 8 * 8 * 8));
    // An 8^3 grid: point (i, j, k) has index i + 9 (j + 9 k); grid coordinate -1 + i / 4.
    ASSERT_EQ(m.pointCount(), 9u * 9u * 9u);
    size_t jittered = 0;
    for (std::uint32_t k = 0; k <= 8; ++k) {
        for (std::uint32_t j = 0; j <= 8; ++j) {
            for (std::uint32_t i = 0; i <= 8; ++i) {
                const Vec3f p = m.points[i + 9 * (j + 9 * k)];
                const std::uint32_t idx[3] = {i, j, k};
                for (int axis = 0; axis < 3; ++axis) {
                    const double grid = -1.0 + idx[axis] / 4.0;
                    if (idx[axis] == 0 || idx[axis] == 8) {
                        EXPECT_EQ(p[axis], static_cast<float>(grid));
                    } else {
                        EXPECT_LE(std::abs(p[axis] - grid), 0.2 * 0.25 + 1e-6);
                        jittered += p[axis] != static_cast<float>(grid);
                    }
                }
            }
        }
    }
    EXPECT_GT(jittered, 7u * 7u * 7u * 2u);
}

TEST(Procedural, ProgressIsReportedFromZeroToOneInAboutOnePercentSteps) {
    std::vector<double> calls;
    ProceduralSpec spec = makeSpec(ProceduralShape::Box, 300000);
    generateMesh(spec, [&](double f) { calls.push_back(f); });
    ASSERT_GE(calls.size(), 50u);
    EXPECT_LE(calls.size(), 300u);
    EXPECT_EQ(calls.front(), 0.0);
    EXPECT_EQ(calls.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(calls.begin(), calls.end()));
}

TEST(Procedural, BadSpecsAndNamesAreArgumentErrors) {
    auto expectArgument = [](auto&& fn, const std::string& text) {
        try {
            fn();
            ADD_FAILURE() << "no error for " << text;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            EXPECT_THAT(e.what(), HasSubstr(text));
        }
    };
    ProceduralSpec spec;
    spec.targetCells = 0;
    expectArgument([&] { generateMesh(spec); }, "targetCells");
    spec = {};
    spec.jitter = 0.3f;
    expectArgument([&] { generateMesh(spec); }, "jitter");
    spec.jitter = -0.1f;
    expectArgument([&] { generateMesh(spec); }, "jitter");
    spec.jitter = NAN;
    expectArgument([&] { generateMesh(spec); }, "jitter");
    spec = {};
    spec.fields = {ProceduralField::Linear, ProceduralField::Linear};
    expectArgument([&] { generateMesh(spec); }, "'linear' is listed twice");
    spec = {};
    spec.targetCells = 1ull << 40;
    expectArgument([&] { generateMesh(spec); }, "32-bit indices");
    expectArgument([] { parseProceduralShape("sphere"); }, "'sphere': expected box, shell");
    expectArgument([] { parseProceduralField("Jet"); }, "expected constant, linear, jet");
    for (ProceduralShape s : kShapes) EXPECT_EQ(parseProceduralShape(proceduralShapeName(s)), s);
    for (ProceduralField f : {ProceduralField::Constant, ProceduralField::Linear,
                              ProceduralField::Jet, ProceduralField::MarschnerLobb})
        EXPECT_EQ(parseProceduralField(proceduralFieldName(f)), f);
}

TEST(Procedural, SizeIsKnownBeforeGenerating) {
    // `generate` and `demo` check --max-memory from these before generating anything.
    for (const ProceduralShape shape :
         {ProceduralShape::Box, ProceduralShape::Shell, ProceduralShape::Graded}) {
        for (const std::uint64_t cells : {1ull, 777ull, 20000ull}) {
            ProceduralSpec spec;
            spec.shape = shape;
            spec.targetCells = cells;
            spec.fields = {ProceduralField::Jet, ProceduralField::Linear};
            const Mesh m = generateMesh(spec);
            EXPECT_EQ(proceduralTetCount(spec), m.cellCount());
            std::uint64_t bytes = m.points.size() * sizeof(Vec3f) + m.cellTypes.size() +
                                  m.cellOffsets.size() * 8 + m.cellIndices.size() * 4;
            for (const Field& f : m.fields) bytes += f.values.size() * 4;
            // Exact up to the one extra cell offset.
            EXPECT_LE(bytes, proceduralMeshBytes(spec) + 8);
            EXPECT_GE(bytes, proceduralMeshBytes(spec));
        }
    }
}

TEST(Procedural, MultiscaleFieldHasDetailDownToTheCellSize) {
    // Mean absolute difference of the field between points a fine cell apart: with octaves down
    // to that cell size it is several times what the same field stopping at a 16x coarser cell
    // has (which is smooth there), and far above the jet's.
    constexpr double kFine = 1.0 / 512, kCoarse = 1.0 / 32;
    double fine = 0.0, coarse = 0.0, jet = 0.0, lo = 1.0, hi = 0.0;
    int n = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3f p(-0.9f + 1.8f * float((i * 37) % 1000) / 1000.f,
                      -0.9f + 1.8f * float((i * 91) % 997) / 997.f,
                      -0.9f + 1.8f * float((i * 53) % 991) / 991.f);
        const Vec3f q = p + Vec3f(float(kFine), 0.f, 0.f);
        const float v = proceduralFieldValue(ProceduralField::Multiscale, p, kFine);
        fine += std::fabs(proceduralFieldValue(ProceduralField::Multiscale, q, kFine) - v);
        coarse += std::fabs(proceduralFieldValue(ProceduralField::Multiscale, q, kCoarse) -
                            proceduralFieldValue(ProceduralField::Multiscale, p, kCoarse));
        jet += std::fabs(proceduralFieldValue(ProceduralField::Jet, q) -
                         proceduralFieldValue(ProceduralField::Jet, p));
        lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
        ++n;
    }
    EXPECT_GT(fine, 2.0 * coarse);
    EXPECT_GT(fine, 10.0 * jet);
    EXPECT_GE(lo, 0.0);
    EXPECT_LE(hi, 1.0);
    EXPECT_GT(hi - lo, 0.5);  // the values span most of [0, 1]
    // A generated mesh stores the field with octaves down to its own cell size.
    ProceduralSpec spec = makeSpec(ProceduralShape::Box, 200000);
    spec.fields = {ProceduralField::Multiscale};
    const Mesh m = generateMesh(spec);
    const double h = proceduralCellSize(spec);
    EXPECT_NEAR(h, 2.0 / 32.0, 0.002);  // about 32 cubes per axis
    int differ = 0;
    for (std::size_t i = 0; i < m.points.size(); ++i) {
        ASSERT_EQ(m.fields[0].values[i],
                  proceduralFieldValue(ProceduralField::Multiscale, m.points[i], h));
        differ += m.fields[0].values[i] !=
                  proceduralFieldValue(ProceduralField::Multiscale, m.points[i], kFine);
    }
    EXPECT_GT(differ, int(m.points.size() / 2));
}

// ---------------------------------------------------------------------------------------------
// generateMixedCellMesh

/// VTK's faces of each cell type (corner indices; orientation does not matter here), written out
/// independently of the generator's tables.
const std::vector<std::vector<int>>& vtkFaces(CellType type) {
    static const std::vector<std::vector<int>> tet = {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 2, 1}};
    static const std::vector<std::vector<int>> pyramid = {
        {0, 1, 2, 3}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
    static const std::vector<std::vector<int>> wedge = {
        {0, 1, 2}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}};
    static const std::vector<std::vector<int>> hex = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                      {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    switch (type) {
        case CellType::Tetra:
            return tet;
        case CellType::Pyramid:
            return pyramid;
        case CellType::Wedge:
            return wedge;
        case CellType::Hexahedron:
            break;
    }
    return hex;
}

/// Every face of a mesh (sorted corner set) with the cells having it, and the face's corners in
/// cyclic order.
struct FaceCensus {
    std::map<std::vector<std::uint32_t>, std::vector<std::uint64_t>> cells;
    std::map<std::vector<std::uint32_t>, std::vector<std::uint32_t>> cyclic;

    explicit FaceCensus(const Mesh& m) {
        for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
            const auto ids = m.cell(c);
            for (const auto& face : vtkFaces(m.cellTypes[c])) {
                std::vector<std::uint32_t> corners;
                for (int v : face) corners.push_back(ids[v]);
                std::vector<std::uint32_t> key = corners;
                std::sort(key.begin(), key.end());
                cells[key].push_back(c);
                cyclic[key] = corners;
            }
        }
    }
};

std::string typeWord(CellType t) {
    switch (t) {
        case CellType::Tetra:
            return "tet";
        case CellType::Pyramid:
            return "pyramid";
        case CellType::Wedge:
            return "wedge";
        case CellType::Hexahedron:
            break;
    }
    return "hex";
}

/// Interior faces by pairing: "quad hex-pyramid", "triangle tet-wedge", ... (types in the order
/// tet, pyramid, wedge, hex).
std::map<std::string, int> facePairings(const Mesh& m) {
    std::map<std::string, int> counts;
    const FaceCensus census(m);
    for (const auto& [key, cells] : census.cells) {
        if (cells.size() != 2) continue;
        CellType a = m.cellTypes[cells[0]], b = m.cellTypes[cells[1]];
        auto rank = [](CellType t) {
            return t == CellType::Tetra     ? 0
                   : t == CellType::Pyramid ? 1
                   : t == CellType::Wedge   ? 2
                                            : 3;
        };
        if (rank(a) > rank(b)) std::swap(a, b);
        ++counts[(key.size() == 4 ? "quad " : "triangle ") + typeWord(a) + "-" + typeWord(b)];
    }
    return counts;
}

/// True when every corner of the face lies on one side of [-1, 1]^3.
bool onBoundary(const Mesh& m, const std::vector<std::uint32_t>& face) {
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.f, 1.f}) {
            bool all = true;
            for (std::uint32_t v : face) all = all && m.points[v][axis] == side;
            if (all) return true;
        }
    return false;
}

TEST(MixedCellMesh, EveryFacePairingOccurs) {
    const std::vector<std::string> expected = {"quad hex-hex",           "quad pyramid-hex",
                                               "quad wedge-hex",         "quad pyramid-pyramid",
                                               "quad pyramid-wedge",     "quad wedge-wedge",
                                               "triangle tet-tet",       "triangle tet-pyramid",
                                               "triangle tet-wedge",     "triangle pyramid-pyramid",
                                               "triangle pyramid-wedge", "triangle wedge-wedge"};
    for (int n : {4, 5, 7}) {
        for (std::uint64_t seed : {1, 2, 3}) {
            SCOPED_TRACE("n " + std::to_string(n) + ", seed " + std::to_string(seed));
            const Mesh m = generateMixedCellMesh(n, 0.1f, seed);
            const auto counts = facePairings(m);
            std::string report;
            for (const auto& [pairing, count] : counts)
                report += pairing + ": " + std::to_string(count) + "; ";
            if (n == 4 && seed == 1) std::cout << "n = 4, seed 1: " << report << "\n";
            for (const std::string& pairing : expected)
                EXPECT_GT(counts.count(pairing) ? counts.at(pairing) : 0, 0)
                    << pairing << " missing: " << report;
            // Nothing else: no quad against a tetrahedron, no triangle against a hexahedron.
            EXPECT_EQ(counts.size(), expected.size()) << report;
        }
    }
}

TEST(MixedCellMesh, IsConforming) {
    for (int n : {1, 2, 3, 4, 6}) {
        for (float jitter : {0.f, 0.15f}) {
            for (std::uint64_t seed : {1, 9}) {
                SCOPED_TRACE("n " + std::to_string(n) + ", jitter " + std::to_string(jitter) +
                             ", seed " + std::to_string(seed));
                const Mesh m = generateMixedCellMesh(n, jitter, seed);
                const FaceCensus census(m);
                std::uint64_t boundary = 0;
                for (const auto& [key, cells] : census.cells) {
                    ASSERT_LE(cells.size(), 2u)
                        << "a face of cells " << cells[0] << ", " << cells[1] << ", " << cells[2];
                    if (onBoundary(m, key)) {
                        EXPECT_EQ(cells.size(), 1u) << "boundary face of cell " << cells[0];
                        ++boundary;
                    } else {
                        EXPECT_EQ(cells.size(), 2u)
                            << "interior face of cell " << cells[0] << " has no neighbour";
                    }
                    if (key.size() != 4) continue;
                    // A quadrilateral is never matched against two triangles.
                    const auto& q = census.cyclic.at(key);
                    for (int skip = 0; skip < 4; ++skip) {
                        std::vector<std::uint32_t> tri;
                        for (int v = 0; v < 4; ++v)
                            if (v != skip) tri.push_back(q[v]);
                        std::sort(tri.begin(), tri.end());
                        EXPECT_EQ(census.cells.count(tri), 0u)
                            << "quad face of cell " << cells[0] << " also split into triangles";
                    }
                }
                // The boundary: 6 n^2 block faces, quads or triangle pairs; area 24.
                double area = 0.0;
                for (const auto& [key, cells] : census.cells) {
                    if (cells.size() != 1) continue;
                    const auto& f = census.cyclic.at(key);
                    for (std::size_t t = 1; t + 1 < f.size(); ++t) {
                        const Vec3f a = m.points[f[0]], b = m.points[f[t]], c = m.points[f[t + 1]];
                        area += 0.5 * double(length(cross(b - a, c - a)));
                    }
                }
                EXPECT_GE(boundary, 6u * n * n);
                EXPECT_NEAR(area, 24.0, 1e-4);
            }
        }
    }
}

TEST(MixedCellMesh, FillsTheCubeWithPositiveCells) {
    for (float jitter : {0.f, 0.1f, 0.15f}) {
        for (std::uint64_t seed = 1; seed <= (jitter == 0.15f ? 12u : 2u); ++seed) {
            SCOPED_TRACE("jitter " + std::to_string(jitter) + ", seed " + std::to_string(seed));
            const Mesh m = generateMixedCellMesh(4, jitter, seed);
            double volume = 0.0;
            for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
                const CellSplit split = splitCell(m, c);
                ASSERT_EQ(split.shape, CellShape::Valid) << "cell " << c;
                for (int t = 0; t < split.count; ++t) volume += split.volume6[t] / 6.0;
                // The native map (trilinear hexahedra, ...) does not fold; VTK-ordered wedges
                // (cell_math.h's wedge map, (0, 1, 2) towards (3, 4, 5), mirrors VTK's order)
                // have a negative Jacobian there, the other types a positive one.
                Vec3f x[8];
                const auto ids = m.cell(c);
                for (std::size_t v = 0; v < ids.size(); ++v) x[v] = m.points[ids[v]];
                const CellKind kind = m.cellTypes[c] == CellType::Tetra     ? CellKind::Tet
                                      : m.cellTypes[c] == CellType::Pyramid ? CellKind::Pyramid
                                      : m.cellTypes[c] == CellType::Wedge   ? CellKind::Wedge
                                                                            : CellKind::Hex;
                EXPECT_EQ(nativeOrientation(kind, x), kind == CellKind::Wedge ? -1 : 1)
                    << "cell " << c;
            }
            EXPECT_NEAR(volume, 8.0, 1e-4);
            const ValidationReport report = validateMesh(m);
            EXPECT_TRUE(report.findings().empty()) << ::testing::PrintToString(report.findings());
            EXPECT_EQ(report.invertedCells + report.distortedCells + report.zeroVolumeCells, 0u);
        }
    }
}

TEST(MixedCellMesh, HexahedronFacesAreNotPlanarWhenJittered) {
    const Mesh m = generateMixedCellMesh(4, 0.1f, 1);
    double worst =
        0.0;  // largest distance of a hexahedron face corner from its other three's plane
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        if (m.cellTypes[c] != CellType::Hexahedron) continue;
        const auto ids = m.cell(c);
        for (const auto& f : vtkFaces(CellType::Hexahedron)) {
            const Vec3f a = m.points[ids[f[0]]], b = m.points[ids[f[1]]], d = m.points[ids[f[3]]],
                        p = m.points[ids[f[2]]];
            const Vec3f nrm = normalize(cross(b - a, d - a));
            worst = std::max(worst, std::fabs(double(dot(p - a, nrm))));
        }
    }
    EXPECT_GT(worst, 0.01);  // the block size is 0.5
}

TEST(MixedCellMesh, HasAllCellTypesAndFields) {
    const int n = 4;
    const Mesh m = generateMixedCellMesh(n, 0.1f, 5);
    for (CellType t : {CellType::Tetra, CellType::Pyramid, CellType::Wedge, CellType::Hexahedron})
        EXPECT_GT(std::count(m.cellTypes.begin(), m.cellTypes.end(), t), 0) << cellTypeName(t);
    const Field* linear = m.findField("linear", Association::Point);
    const Field* product = m.findField("xyz", Association::Point);
    const Field* block = m.findField("block", Association::Cell);
    const Field* types = m.findField("cell_type", Association::Cell);
    ASSERT_TRUE(linear && product && block && types);
    ASSERT_EQ(linear->values.size(), m.pointCount());
    ASSERT_EQ(product->values.size(), m.pointCount());
    for (std::uint64_t i = 0; i < m.pointCount(); ++i) {
        const Vec3f p = m.points[i];
        EXPECT_NEAR(linear->values[i], p.x + 2.0 * p.y - p.z, 1e-6);
        EXPECT_NEAR(product->values[i], double(p.x) * p.y * p.z, 1e-6);
    }
    ASSERT_EQ(block->values.size(), m.cellCount());
    ASSERT_EQ(types->values.size(), m.cellCount());
    const double h = 2.0 / n;
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        EXPECT_EQ(types->values[c], float(m.cellTypes[c]));
        // The cell's corners lie in (or, jittered, by its side of) its block.
        const auto b = static_cast<std::uint64_t>(block->values[c]);
        ASSERT_LT(b, std::uint64_t(n * n * n));
        const double lo[3] = {-1.0 + h * double(b % n), -1.0 + h * double(b / n % n),
                              -1.0 + h * double(b / n / n)};
        for (std::uint32_t v : m.cell(c))
            for (int a = 0; a < 3; ++a) {
                EXPECT_GE(m.points[v][a], lo[a] - 0.1 * h - 1e-6);
                EXPECT_LE(m.points[v][a], lo[a] + 1.1 * h + 1e-6);
            }
    }
    ASSERT_FALSE(m.notes.empty());
    EXPECT_THAT(m.notes[0], HasSubstr("4^3 blocks"));
}

TEST(MixedCellMesh, SameSeedSameMesh) {
    const Mesh a = generateMixedCellMesh(5, 0.12f, 42), b = generateMixedCellMesh(5, 0.12f, 42);
    ASSERT_EQ(a.points.size(), b.points.size());
    EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
    EXPECT_EQ(a.cellTypes, b.cellTypes);
    EXPECT_EQ(a.cellOffsets, b.cellOffsets);
    EXPECT_EQ(a.cellIndices, b.cellIndices);
    ASSERT_EQ(a.fields.size(), b.fields.size());
    for (std::size_t f = 0; f < a.fields.size(); ++f)
        EXPECT_EQ(a.fields[f].values, b.fields[f].values);
    const Mesh c = generateMixedCellMesh(5, 0.12f, 43);
    EXPECT_FALSE(a.points.size() == c.points.size() &&
                 std::memcmp(a.points.data(), c.points.data(), a.points.size() * sizeof(Vec3f)) ==
                     0);
}

TEST(MixedCellMesh, BadArgumentsAreArgumentErrors) {
    auto expectArgument = [](int n, float jitter, const std::string& text) {
        try {
            generateMixedCellMesh(n, jitter, 1);
            ADD_FAILURE() << "no error for n " << n << ", jitter " << jitter;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            EXPECT_THAT(e.what(), HasSubstr(text));
        }
    };
    expectArgument(0, 0.1f, "blocks per axis must be in [1, 1000], got 0");
    expectArgument(-3, 0.1f, "got -3");
    expectArgument(kMaxMixedCellBlocks + 1, 0.1f, "got 1001");
    expectArgument(4, -0.01f, "jitter must be in [0, 0.15");
    expectArgument(4, 0.16f, "jitter must be in [0, 0.15");
    expectArgument(4, std::numeric_limits<float>::quiet_NaN(), "jitter");
}

}  // namespace
}  // namespace uvr

namespace uvr {
namespace {

TEST(ProceduralStream, SameBytesAsTheMeshWrittenWhole) {
    const std::string dir = testing::scratchDir();
    struct Case {
        ProceduralSpec spec;
        std::uint64_t slabTets;
    };
    std::vector<Case> cases;
    cases.push_back({makeSpec(ProceduralShape::Box, 5), kProceduralSlabTets});
    cases.push_back({makeSpec(ProceduralShape::Box, 30000, 3), kProceduralSlabTets});
    cases.push_back({makeSpec(ProceduralShape::Box, 30000, 3), 1000});  // many slabs
    cases.push_back({makeSpec(ProceduralShape::Graded, 20000, 5), 1});  // a layer a slab
    cases.push_back({makeSpec(ProceduralShape::Shell, 20000), 3000});
    ProceduralSpec timed = makeSpec(ProceduralShape::Box, 8000);
    timed.fields = {ProceduralField::Multiscale, ProceduralField::Linear};
    timed.time = 0.7;
    timed.jitter = kMaxProceduralJitter;
    cases.push_back({timed, 500});
    ProceduralSpec noFields = makeSpec(ProceduralShape::Graded, 4000);
    noFields.fields.clear();
    cases.push_back({noFields, 700});
    for (size_t c = 0; c < cases.size(); ++c) {
        SCOPED_TRACE("case " + std::to_string(c));
        const std::string whole = dir + "/whole.uvrm", streamed = dir + "/streamed.uvrm";
        writeNative(generateMesh(cases[c].spec), whole);
        std::vector<double> calls;
        writeProceduralNative(
            cases[c].spec, streamed, [&](double f) { calls.push_back(f); }, cases[c].slabTets);
        const std::string a = testing::readFile(whole), b = testing::readFile(streamed);
        ASSERT_FALSE(a.empty());
        EXPECT_EQ(a.size(), b.size());
        EXPECT_TRUE(a == b) << "first difference at byte "
                            << std::mismatch(a.begin(), a.end(), b.begin(), b.end()).first -
                                   a.begin();
        ASSERT_FALSE(calls.empty());
        EXPECT_EQ(calls.front(), 0.0);
        EXPECT_EQ(calls.back(), 1.0);
        EXPECT_TRUE(std::is_sorted(calls.begin(), calls.end()));
    }
    // Nothing but the two outputs is left in the folder (the temporary was renamed).
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                            std::filesystem::directory_iterator()),
              2);
}

TEST(ProceduralStream, PeakEstimateIsSmallForLargeMeshes) {
    ProceduralSpec spec = makeSpec(ProceduralShape::Box, 1000000000);
    EXPECT_LT(proceduralStreamBytes(spec), 600ull << 20);
    EXPECT_GT(proceduralMeshBytes(spec), 20000000000ull);
    EXPECT_THROW(writeProceduralNative(makeSpec(ProceduralShape::Box, 0), "/nonexistent/x.uvrm"),
                 Error);
}

}  // namespace
}  // namespace uvr

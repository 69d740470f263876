// SPDX-License-Identifier: MIT
#include "uvr/mesh/validate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/threads.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {
namespace {

Mesh unitTet() {
    Mesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const std::uint32_t ids[4] = {0, 1, 2, 3};
    m.addCell(CellType::Tetra, ids);
    return m;
}

TEST(Validate, CleanMeshHasNoFindings) {
    EXPECT_TRUE(validateMesh(unitTet()).findings().empty());
}

TEST(Validate, OutOfRangeIndexNamesTheCell) {
    Mesh m = unitTet();
    const std::uint32_t ids[4] = {0, 1, 2, 9};
    m.addCell(CellType::Tetra, ids);
    try {
        validateMesh(m, "m.vtk");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Validation);
        EXPECT_STREQ(e.what(),
                     "m.vtk: cell 1 (tetra): corner 3 is point 9, expected below pointCount 4");
    }
}

TEST(Validate, FieldSizeMismatchIsAnError) {
    Mesh m = unitTet();
    m.fields.push_back({"p", Association::Point, 1, {1, 2, 3}});
    EXPECT_THROW(validateMesh(m), Error);
}

TEST(Validate, NonFiniteValuesAndCoincidentPointsAreCounted) {
    Mesh m = unitTet();
    m.points.push_back({1, 0, 0});  // coincident with point 1, used by no cell
    m.fields.push_back({"p", Association::Point, 1, {1, NAN, 3, INFINITY, 5}});
    const ValidationReport r = validateMesh(m);
    EXPECT_EQ(r.coincidentPoints, 1u);
    EXPECT_EQ(r.unusedPoints, 1u);
    ASSERT_EQ(r.nonFiniteFields.size(), 1u);
    EXPECT_EQ(r.nonFiniteFields[0].count, 2u);
    EXPECT_EQ(r.nonFiniteFields[0].firstTuple, 1u);
    EXPECT_EQ(r.findings().size(), 3u);
}

TEST(Validate, BoundsAreThoseOfTheRenderedCells) {
    // An unused NaN point, an unused far point, and a flat cell far away lie outside the bounds;
    // so does a cell using a NaN point.
    Mesh m = unitTet();
    m.points.push_back({NAN, 0, 0});
    m.points.push_back({1e30f, 0, 0});
    m.points.push_back({-50, -50, -50});
    m.points.push_back({-50, -40, -50});
    m.points.push_back({-40, -50, -50});
    m.points.push_back({-45, -45, -50});  // all four in z = -50: a flat tetrahedron
    const std::uint32_t flat[4] = {6, 7, 8, 9};
    m.addCell(CellType::Tetra, flat);
    const std::uint32_t withNan[4] = {1, 2, 3, 4};
    m.addCell(CellType::Tetra, withNan);
    const ValidationReport r = validateMesh(m);
    EXPECT_EQ(r.bounds.lo, Vec3f(0.f));
    EXPECT_EQ(r.bounds.hi, Vec3f(1.f));
    EXPECT_EQ(r.nonFinitePoints, 1u);
    EXPECT_EQ(r.unusedPoints, 1u);
    // Mesh::bounds leaves out the NaN point, its cell and unused points, not the flat cell.
    const Bounds3f b = m.bounds();
    EXPECT_EQ(b.lo, Vec3f(-50.f));
    EXPECT_EQ(b.hi, Vec3f(1.f));
    // Nothing rendered: empty bounds.
    Mesh flatOnly;
    flatOnly.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3f, 0.3f, 1e-7f}};
    const std::uint32_t ids[4] = {0, 1, 2, 3};
    flatOnly.addCell(CellType::Tetra, ids);
    EXPECT_TRUE(validateMesh(flatOnly).bounds.empty());
    EXPECT_FALSE(flatOnly.bounds().empty());
}

/// validateMesh's findings computed the straightforward way, one cell and one point after the
/// other: the oracle of the parallel validateMesh.
ValidationReport serialReport(const Mesh& mesh) {
    ValidationReport r;
    std::vector<bool> used(mesh.pointCount(), false);
    for (std::uint64_t c = 0; c < mesh.cellCount(); ++c) {
        for (std::uint32_t id : mesh.cell(c)) used[id] = true;
        const CellSplit split = splitCell(mesh, c);
        for (int t = 0; t < split.count; ++t)
            for (std::uint32_t v : split.tets[t].v) r.bounds.extend(mesh.points[v]);
        if (split.shape == CellShape::Inverted && r.invertedCells++ == 0) r.firstInvertedCell = c;
        if (split.shape == CellShape::ZeroVolume && r.zeroVolumeCells++ == 0)
            r.firstZeroVolumeCell = c;
        if (split.shape == CellShape::Distorted && r.distortedCells++ == 0)
            r.firstDistortedCell = c;
    }
    r.unusedPoints = static_cast<std::uint64_t>(std::count(used.begin(), used.end(), false));
    std::vector<std::tuple<float, float, float>> finite;
    for (const Vec3f& p : mesh.points) {
        if (!isFinite(p))
            ++r.nonFinitePoints;
        else
            finite.emplace_back(p.x, p.y, p.z);
    }
    std::sort(finite.begin(), finite.end());
    for (std::size_t i = 1; i < finite.size(); ++i)
        r.coincidentPoints += finite[i] == finite[i - 1];
    for (const Field& f : mesh.fields) {
        NonFiniteField nf{f.name, f.association, 0, 0};
        for (std::size_t i = 0; i < f.values.size(); ++i)
            if (!std::isfinite(f.values[i]) && nf.count++ == 0) nf.firstTuple = i / f.components;
        if (nf.count) r.nonFiniteFields.push_back(nf);
    }
    return r;
}

void expectSameReport(const ValidationReport& a, const ValidationReport& b) {
    EXPECT_EQ(a.invertedCells, b.invertedCells);
    EXPECT_EQ(a.firstInvertedCell, b.firstInvertedCell);
    EXPECT_EQ(a.zeroVolumeCells, b.zeroVolumeCells);
    EXPECT_EQ(a.firstZeroVolumeCell, b.firstZeroVolumeCell);
    EXPECT_EQ(a.distortedCells, b.distortedCells);
    EXPECT_EQ(a.firstDistortedCell, b.firstDistortedCell);
    EXPECT_EQ(a.coincidentPoints, b.coincidentPoints);
    EXPECT_EQ(a.nonFinitePoints, b.nonFinitePoints);
    EXPECT_EQ(a.unusedPoints, b.unusedPoints);
    EXPECT_EQ(a.bounds.lo, b.bounds.lo);
    EXPECT_EQ(a.bounds.hi, b.bounds.hi);
    ASSERT_EQ(a.nonFiniteFields.size(), b.nonFiniteFields.size());
    for (std::size_t i = 0; i < a.nonFiniteFields.size(); ++i) {
        EXPECT_EQ(a.nonFiniteFields[i].name, b.nonFiniteFields[i].name);
        EXPECT_EQ(a.nonFiniteFields[i].count, b.nonFiniteFields[i].count);
        EXPECT_EQ(a.nonFiniteFields[i].firstTuple, b.nonFiniteFields[i].firstTuple);
    }
    EXPECT_EQ(a.findings(), b.findings());
}

TEST(Validate, ParallelReportEqualsASerialOne) {
    // A procedural box of several chunks of cells with every finding planted in later chunks:
    // inverted and flat tetrahedra, a twisted hexahedron, coincident points (one at -0 where the
    // other is at +0), NaN points used and unused, NaN field values.
    ProceduralSpec spec;
    spec.targetCells = 60000;
    spec.fields = {ProceduralField::Linear};
    Mesh m = generateMesh(spec);
    const std::uint64_t n = m.cellCount(), points = m.pointCount();
    ASSERT_GT(n, 40000u);
    for (std::uint64_t c : {n / 3, n / 3 + 1, 2 * n / 3 + 17, n - 5}) {  // inverted
        const std::uint64_t o = m.cellOffsets[c];
        std::swap(m.cellIndices[o + 1], m.cellIndices[o + 2]);
    }
    for (std::uint64_t c : {n / 2 + 3, 5 * n / 6})  // zero volume: a repeated corner
        m.cellIndices[m.cellOffsets[c] + 3] = m.cellIndices[m.cellOffsets[c]];
    const std::uint32_t base = static_cast<std::uint32_t>(m.points.size());
    // A hexahedron whose top face is turned half a turn: tetrahedra of both orientations.
    for (const Vec3f& p : {Vec3f(5, 0, 0), Vec3f(6, 0, 0), Vec3f(6, 1, 0), Vec3f(5, 1, 0),
                           Vec3f(6, 1, 1), Vec3f(5, 1, 1), Vec3f(5, 0, 1), Vec3f(6, 0, 1)})
        m.points.push_back(p);
    const std::uint32_t hex[8] = {base,     base + 1, base + 2, base + 3,
                                  base + 4, base + 5, base + 6, base + 7};
    m.addCell(CellType::Hexahedron, hex);
    m.points.push_back(m.points[7]);           // coincident, unused
    m.points.push_back(m.points[123]);         // coincident, unused
    m.points.push_back({0.f, 0.f, 0.f});       // +0
    m.points.push_back({-0.f, 0.f, -0.f});     // coincident with it
    m.points.push_back({NAN, 0.f, 0.f});       // non-finite, unused
    m.points.push_back({1.f, INFINITY, 0.f});  // non-finite, used below
    const std::uint32_t withInf[4] = {0, 1, 2, static_cast<std::uint32_t>(m.points.size() - 1)};
    m.addCell(CellType::Tetra, withInf);
    for (Field& f : m.fields)
        if (f.association == Association::Point) {
            f.values.resize(m.points.size() * f.components, 1.f);
            f.values[points / 2 * f.components] = NAN;
            f.values[(points - 10) * f.components] = -INFINITY;
        }
    m.fields.push_back({"c", Association::Cell, 1, std::vector<float>(m.cellCount(), 2.f)});
    m.fields.back().values[n / 2] = NAN;
    const ValidationReport serial = serialReport(m);
    EXPECT_EQ(serial.invertedCells, 4u);
    EXPECT_EQ(serial.zeroVolumeCells, 3u);  // with the cell of the infinite point
    EXPECT_EQ(serial.distortedCells, 1u);
    EXPECT_GE(serial.coincidentPoints, 3u);
    EXPECT_EQ(serial.nonFinitePoints, 2u);
    for (int threads : {1, 2, 3}) {
        SCOPED_TRACE(threads);
        cpu::setThreadCount(threads);
        expectSameReport(validateMesh(m), serial);
    }
    cpu::setThreadCount(0);
}

// The data README documents these counts for the classic data sets.
TEST(Validate, BluntFinHas77ZeroVolumeTetsAnd39CoincidentPoints) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const ValidationReport r = validateMesh(readMesh(testing::sharedData("bluntfin_tets.vtk")));
    EXPECT_EQ(r.zeroVolumeCells, 77u);
    EXPECT_EQ(r.coincidentPoints, 39u);
    EXPECT_EQ(r.invertedCells, 0u);
}

TEST(Validate, OxygenPostHas1444CoincidentPoints) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const ValidationReport r = validateMesh(readMesh(testing::sharedData("post_tets.vtk")));
    EXPECT_EQ(r.coincidentPoints, 1444u);
    EXPECT_EQ(r.invertedCells, 0u);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/mesh/validate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/mesh/io/mesh_reader.h"

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

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

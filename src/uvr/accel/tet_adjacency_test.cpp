// SPDX-License-Identifier: MIT
#include "uvr/accel/tet_adjacency.h"

#include <gtest/gtest.h>

#include <random>

#include "uvr/cpu/threads.h"

namespace uvr {
namespace {

TEST(CoincidentPoints, EachPointMapsToTheFirstAtItsPosition) {
    const std::vector<Vec3f> pts = {{0, 0, 0}, {1, 0, 0},    {0, 0, 0},   {2, 0, 0},
                                    {1, 0, 0}, {-0.f, 0, 0}, {NAN, 0, 0}, {NAN, 0, 0}};
    const std::vector<std::uint32_t> expected = {0, 1, 0, 3, 1, 0, 6, 7};  // -0 == 0; NaN alone
    EXPECT_EQ(coincidentPointIds(pts), expected);
    EXPECT_TRUE(coincidentPointIds({}).empty());
}

TEST(CoincidentPoints, SameResultWhateverTheThreadCount) {
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> coord(0, 40);  // many exact duplicates
    std::vector<Vec3f> pts(200000);
    for (Vec3f& p : pts) p = Vec3f(float(coord(rng)), float(coord(rng)), float(coord(rng) % 4));
    cpu::setThreadCount(1);
    const std::vector<std::uint32_t> one = coincidentPointIds(pts);
    cpu::setThreadCount(2);
    const std::vector<std::uint32_t> two = coincidentPointIds(pts);
    cpu::setThreadCount(0);
    EXPECT_EQ(one, two);
    for (std::size_t i = 0; i < pts.size(); ++i) {
        ASSERT_LE(one[i], i);
        ASSERT_TRUE(pts[one[i]] == pts[i]);
        ASSERT_EQ(one[one[i]], one[i]);  // the representative represents itself
    }
}

// Two tetrahedra on either side of the face (1, 2, 3), the second one written with copies of
// those three points (a seam): they are neighbours all the same.
TEST(TetNeighbors, FacesAcrossASeamOfDuplicatedPointsMatch) {
    TetMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                   {1, 1, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    mesh.tets = {Tet{{0, 1, 2, 3}}, Tet{{4, 7, 6, 5}}};
    const std::vector<std::uint32_t> nb = buildTetNeighbors(mesh);
    ASSERT_EQ(nb.size(), 8u);
    EXPECT_EQ(nb[0], 1u);  // face opposite vertex 0 of tet 0: (1, 2, 3)
    EXPECT_EQ(nb[4], 0u);  // face opposite vertex 4 of tet 1: (7, 6, 5), the same positions
    for (int i : {1, 2, 3, 5, 6, 7}) EXPECT_EQ(nb[i], kNoTet) << i;
    // Moved off the shared face, the copies no longer coincide: no neighbours.
    mesh.points[5].x = 1.001f;
    const std::vector<std::uint32_t> apart = buildTetNeighbors(mesh);
    EXPECT_EQ(apart[0], kNoTet);
    EXPECT_EQ(apart[4], kNoTet);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/mesh/refine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/core/error.h"
#include "uvr/cpu/threads.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {
namespace {

float linear(Vec3f p) {
    return p.x + 2 * p.y - p.z;
}

/// A jittered n^3 hex grid over [-1, 1]^3 with the point field f = x + 2y - z and a cell field
/// "id" holding each cell's index.
Mesh idHexGrid(int n) {
    Mesh m = testing::makeHexGrid(n, -1.f, 1.f, linear, 0.3f);
    Field id{"id", Association::Cell, 1, {}};
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) id.values.push_back(float(c));
    m.fields.push_back(std::move(id));
    return m;
}

double signedVolume(const Mesh& m, std::uint64_t c) {
    const auto v = m.cell(c);
    const Vec3f a = m.points[v[0]], b = m.points[v[1]], p = m.points[v[2]], d = m.points[v[3]];
    const double bx = double(b.x) - a.x, by = double(b.y) - a.y, bz = double(b.z) - a.z;
    const double cx = double(p.x) - a.x, cy = double(p.y) - a.y, cz = double(p.z) - a.z;
    const double dx = double(d.x) - a.x, dy = double(d.y) - a.y, dz = double(d.z) - a.z;
    return (bx * (cy * dz - cz * dy) - by * (cx * dz - cz * dx) + bz * (cx * dy - cy * dx)) / 6.0;
}

TEST(Refine, MultipliesTetsBy8AndKeepsVolumeFieldsAndConformity) {
    constexpr int kN = 4, kLevels = 2;
    const Mesh in = idHexGrid(kN);
    const TetMesh base =
        tetrahedralize(in, {"f", Association::Point, in.fields[0].values}, {.splitCells = true});
    const Mesh out = refineMesh(in, kLevels);
    ASSERT_EQ(out.cellCount(), base.tets.size() * 64);
    // Volume: every child positive, their sum the parent volume (midpoints rounded to float).
    double volume = 0.0;
    for (std::uint64_t c = 0; c < out.cellCount(); ++c) {
        ASSERT_EQ(out.cellTypes[c], CellType::Tetra);
        const double v = signedVolume(out, c);
        ASSERT_GT(v, 0.0) << "tetrahedron " << c;
        volume += v;
    }
    constexpr double kRelativeVolumeTolerance = 1e-6;  // relative; float midpoints
    EXPECT_NEAR(volume, base.totalVolume, kRelativeVolumeTolerance * base.totalVolume);
    EXPECT_NEAR(volume, 8.0, 1e-5);  // the grid spans [-1, 1]^3 whatever the interior jitter
    // The linear point field is reproduced at every new point; cell values follow their cell.
    ASSERT_EQ(out.fields.size(), 2u);
    constexpr float kFieldTolerance = 1e-5f;
    for (std::uint64_t p = 0; p < out.pointCount(); ++p)
        ASSERT_NEAR(out.fields[0].values[p], linear(out.points[p]), kFieldTolerance) << p;
    for (std::uint64_t c = 0; c < out.cellCount(); ++c) {
        // Hexahedra split into 5 or 6 tetrahedra: find the source cell by the children's centre.
        const auto v = out.cell(c);
        Vec3f centre =
            (out.points[v[0]] + out.points[v[1]] + out.points[v[2]] + out.points[v[3]]) * 0.25f;
        const float id = out.fields[1].values[c];
        ASSERT_EQ(id, std::floor(id));
        const auto src = in.cell(static_cast<std::uint64_t>(id));
        Bounds3f box;
        for (std::uint32_t s : src) box.extend(in.points[s]);
        ASSERT_TRUE(box.contains(centre)) << c;
    }
    // Conforming: every interior face has exactly one neighbour, and the boundary is the input
    // boundary (12 n^2 triangles) with each triangle split into 4 per level.
    TetMesh tets;
    tets.points = out.points;
    for (std::uint64_t c = 0; c < out.cellCount(); ++c) {
        const auto v = out.cell(c);
        tets.tets.push_back({{v[0], v[1], v[2], v[3]}});
    }
    const auto nb = buildTetNeighbors(tets);
    std::uint64_t boundary = 0;
    for (std::uint64_t t = 0; t < tets.tets.size(); ++t)
        for (int i = 0; i < 4; ++i) {
            const std::uint32_t o = nb[4 * t + i];
            if (o == kNoTet) {
                ++boundary;
                continue;
            }
            int back = 0;
            for (int j = 0; j < 4; ++j) back += nb[4 * o + j] == t;
            ASSERT_EQ(back, 1);
        }
    EXPECT_EQ(boundary, 12u * kN * kN * 16u);
    // Corner points keep their indices and positions.
    for (std::uint64_t p = 0; p < in.pointCount(); ++p)
        ASSERT_EQ(std::memcmp(&in.points[p], &out.points[p], sizeof(Vec3f)), 0);
}

TEST(Refine, ZeroLevelsSplitsOnly) {
    const Mesh in = idHexGrid(2);
    const Mesh out = refineMesh(in, 0);
    const TetMesh base =
        tetrahedralize(in, {"f", Association::Point, in.fields[0].values}, {.splitCells = true});
    EXPECT_EQ(out.cellCount(), base.tets.size());
    EXPECT_EQ(out.pointCount(), in.pointCount());
}

TEST(Refine, SameOutputWhateverTheThreadCount) {
    const Mesh in = idHexGrid(8);
    cpu::setThreadCount(1);
    const Mesh one = refineMesh(in, 2);
    cpu::setThreadCount(2);
    const Mesh two = refineMesh(in, 2);
    cpu::setThreadCount(0);
    ASSERT_EQ(one.points.size(), two.points.size());
    EXPECT_EQ(std::memcmp(one.points.data(), two.points.data(), one.points.size() * sizeof(Vec3f)),
              0);
    EXPECT_EQ(one.cellIndices, two.cellIndices);
    ASSERT_EQ(one.fields.size(), two.fields.size());
    for (std::size_t f = 0; f < one.fields.size(); ++f)
        EXPECT_EQ(std::memcmp(one.fields[f].values.data(), two.fields[f].values.data(),
                              one.fields[f].values.size() * sizeof(float)),
                  0);
}

TEST(Refine, BadLevelsAreArgumentErrors) {
    const Mesh in = idHexGrid(1);
    for (int levels : {-1, kMaxRefineLevels + 1}) {
        try {
            refineMesh(in, levels);
            FAIL() << levels;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
        }
    }
    // 6 tetrahedra * 8^8 = 100M fits, but a bigger grid would pass kMaxRefinedTets.
    try {
        refineMesh(idHexGrid(3), kMaxRefineLevels);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Resource);
    }
}

}  // namespace
}  // namespace uvr

namespace uvr {
namespace {

TEST(RefineStream, SameBytesAsTheRefinedMeshWrittenWhole) {
    const std::string dir = testing::scratchDir();
    // A hex grid with a point and a cell field; a mixed-cell mesh with two of each and a vector
    // point field added; levels 0 to 2; pieces of every size.
    Mesh mixed = generateMixedCellMesh(3);
    Field vec{"vec", Association::Point, 3, {}};
    for (const Vec3f& p : mixed.points) vec.values.insert(vec.values.end(), {p.x, p.y, -p.z});
    mixed.fields.insert(mixed.fields.begin() + 1, std::move(vec));
    struct Case {
        const Mesh* mesh;
        int levels;
        std::uint64_t pieceTets;
    };
    const Mesh grid = idHexGrid(4);
    const std::vector<Case> cases = {{&grid, 1, kRefinePieceTets},
                                     {&grid, 2, 7},
                                     {&grid, 0, 5},
                                     {&mixed, 1, 1},
                                     {&mixed, 2, 100},
                                     {&mixed, 0, kRefinePieceTets}};
    for (size_t c = 0; c < cases.size(); ++c) {
        SCOPED_TRACE("case " + std::to_string(c));
        const std::string whole = dir + "/whole.uvrm", streamed = dir + "/streamed.uvrm";
        writeNative(refineMesh(*cases[c].mesh, cases[c].levels), whole);
        std::vector<double> calls;
        refineToNative(
            *cases[c].mesh, cases[c].levels, streamed, {}, [&](double f) { calls.push_back(f); },
            cases[c].pieceTets);
        const std::string a = testing::readFile(whole), b = testing::readFile(streamed);
        ASSERT_FALSE(a.empty());
        EXPECT_EQ(a.size(), b.size());
        EXPECT_TRUE(a == b) << "first difference at byte "
                            << std::mismatch(a.begin(), a.end(), b.begin(), b.end()).first -
                                   a.begin();
        ASSERT_FALSE(calls.empty());
        EXPECT_TRUE(std::is_sorted(calls.begin(), calls.end()));
        EXPECT_EQ(calls.back(), 1.0);
    }
}

TEST(RefineStream, StreamedPeakEstimateIsBelowTheWholeOutput) {
    // 1.3M tetrahedra in, 84M out in 2 levels (only the counts are used).
    const Mesh grid = idHexGrid(60);
    const std::uint64_t tets = 6 * grid.cellCount();
    EXPECT_LT(refineMemoryBytes(grid, tets, 2, true), refineMemoryBytes(grid, tets, 2) / 4);
    EXPECT_LT(refineMemoryBytes(grid, tets, 2, true), 10 * refinedTetCount(tets, 2));
    EXPECT_THROW(refineToNative(idHexGrid(2), 9, testing::scratchDir() + "/x.uvrm"), Error);
}

}  // namespace
}  // namespace uvr

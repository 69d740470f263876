// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

#include "test_meshes.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/mesh/validate.h"

namespace uvr {
namespace {

constexpr double kVolumeTolerance = 1e-5;

/// Mesh of one cell of the given type over unit-cube corners, with global ids permuted.
Mesh oneCell(CellType type, const std::vector<Vec3f>& corners,
             const std::vector<std::uint32_t>& perm) {
    Mesh m;
    m.points.resize(corners.size());
    std::vector<std::uint32_t> ids(corners.size());
    for (size_t i = 0; i < corners.size(); ++i) {
        ids[i] = perm[i];
        m.points[perm[i]] = corners[i];
    }
    m.addCell(type, ids);
    return m;
}

double splitVolume(const Mesh& m, CellShape& shape, int& count) {
    const CellSplit s = splitCell(m, 0);
    shape = s.shape;
    count = s.count;
    double v = 0;
    for (int t = 0; t < s.count; ++t) {
        const Tet& tet = s.tets[t];
        const float v6 = signedVolume6(m.points[tet.v[0]], m.points[tet.v[1]], m.points[tet.v[2]],
                                       m.points[tet.v[3]]);
        EXPECT_GT(v6, 0.f);
        v += v6 / 6.0;
    }
    return v;
}

const std::vector<Vec3f> kCube = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

TEST(Tetrahedralize, EveryHexNumberingGivesSixPositiveTetsFillingTheCube) {
    std::vector<std::uint32_t> perm(8);
    std::iota(perm.begin(), perm.end(), 0u);
    int cases = 0;
    do {
        CellShape shape;
        int count;
        const double v = splitVolume(oneCell(CellType::Hexahedron, kCube, perm), shape, count);
        ASSERT_EQ(count, 6);
        ASSERT_EQ(shape, CellShape::Valid);
        ASSERT_NEAR(v, 1.0, kVolumeTolerance);
        ++cases;
    } while (std::next_permutation(perm.begin(), perm.end()));
    EXPECT_EQ(cases, 40320);
}

TEST(Tetrahedralize, EveryWedgeAndPyramidNumberingFillsTheCell) {
    const std::vector<Vec3f> wedge = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0},
                                      {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    // VTK's wedge: (0,1,2) has its normal pointing away from (3,4,5).
    const std::vector<Vec3f> vtkWedge = {wedge[0], wedge[2], wedge[1],
                                         wedge[3], wedge[5], wedge[4]};
    std::vector<std::uint32_t> perm(6);
    std::iota(perm.begin(), perm.end(), 0u);
    do {
        CellShape shape;
        int count;
        ASSERT_NEAR(splitVolume(oneCell(CellType::Wedge, vtkWedge, perm), shape, count), 0.5,
                    kVolumeTolerance);
        ASSERT_EQ(count, 3);
        ASSERT_EQ(shape, CellShape::Valid);
    } while (std::next_permutation(perm.begin(), perm.end()));
    const std::vector<Vec3f> pyramid = {
        {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
    perm.resize(5);
    std::iota(perm.begin(), perm.end(), 0u);
    do {
        CellShape shape;
        int count;
        ASSERT_NEAR(splitVolume(oneCell(CellType::Pyramid, pyramid, perm), shape, count), 1.0 / 3,
                    kVolumeTolerance);
        ASSERT_EQ(count, 2);
        ASSERT_EQ(shape, CellShape::Valid);
    } while (std::next_permutation(perm.begin(), perm.end()));
}

TEST(Tetrahedralize, NeighbouringHexesSplitSharedFacesTheSameWay) {
    // A 4^3 hex grid with randomly renumbered points: the split must be conforming, i.e. every
    // triangle is shared by two tetrahedra except the 2 * 6 * 16 boundary triangles.
    Mesh grid = testing::makeHexGrid(4, 0.f, 1.f);
    std::vector<std::uint32_t> perm(grid.pointCount());
    std::iota(perm.begin(), perm.end(), 0u);
    std::shuffle(perm.begin(), perm.end(), std::mt19937(42));
    Mesh m = grid;
    for (size_t i = 0; i < perm.size(); ++i) m.points[perm[i]] = grid.points[i];
    for (auto& id : m.cellIndices) id = perm[id];
    m.fields.clear();
    const TetMesh tets = tetrahedralize(
        m, ScalarField{"c", Association::Cell, std::vector<float>(m.cellCount(), 1.f)},
        {.splitCells = true});
    ASSERT_EQ(tets.tets.size(), 6u * 64u);
    std::map<std::array<std::uint32_t, 3>, int> faces;
    for (const Tet& t : tets.tets)
        for (int i = 0; i < 4; ++i) {
            std::array<std::uint32_t, 3> f;
            int k = 0;
            for (int j = 0; j < 4; ++j)
                if (j != i) f[k++] = t.v[j];
            std::sort(f.begin(), f.end());
            ++faces[f];
        }
    int boundary = 0;
    for (const auto& [f, n] : faces) {
        ASSERT_LE(n, 2);
        boundary += n == 1;
    }
    EXPECT_EQ(boundary, 2 * 6 * 16);
    EXPECT_NEAR(tets.totalVolume, 1.0, kVolumeTolerance);
}

TEST(Tetrahedralize, InvertedCellsAreReorientedAndZeroVolumeCellsDropped) {
    Mesh m;
    m.points = kCube;
    const std::uint32_t inverted[8] = {4, 5, 6, 7, 0, 1, 2, 3};  // top and bottom swapped
    m.addCell(CellType::Hexahedron, inverted);
    // A flat tetrahedron (all in z = 0) and a tetrahedron with mirrored order.
    const std::uint32_t flat[4] = {0, 1, 2, 3};
    m.addCell(CellType::Tetra, flat);
    const std::uint32_t mirrored[4] = {0, 2, 1, 4};
    m.addCell(CellType::Tetra, mirrored);
    const ValidationReport r = validateMesh(m);
    EXPECT_EQ(r.invertedCells, 2u);
    EXPECT_EQ(r.firstInvertedCell, 0u);
    EXPECT_EQ(r.zeroVolumeCells, 1u);
    EXPECT_EQ(r.firstZeroVolumeCell, 1u);
    const TetMesh t = tetrahedralize(m, ScalarField{"c", Association::Cell, {1.f, 2.f, 3.f}},
                                     {.splitCells = true});
    ASSERT_EQ(t.tets.size(), 7u);
    for (const Tet& tet : t.tets)
        EXPECT_GT(signedVolume6(t.points[tet.v[0]], t.points[tet.v[1]], t.points[tet.v[2]],
                                t.points[tet.v[3]]),
                  0.f);
    EXPECT_NEAR(t.totalVolume, 1.0 + 1.0 / 6, kVolumeTolerance);
    // Cell data follows its cell: in cell order six tets of value 1, then the mirrored tet's 3,
    // wherever the Morton order put them.
    ASSERT_EQ(t.tetSourceOrder.size(), 7u);
    for (std::size_t i = 0; i < 7; ++i)
        EXPECT_EQ(t.values[i], t.tetSourceOrder[i] == 6 ? 3.f : 1.f) << "tetrahedron " << i;
    const TetMesh inCellOrder =
        tetrahedralize(m, ScalarField{"c", Association::Cell, {1.f, 2.f, 3.f}},
                       {.splitCells = true, .spatialOrder = false});
    EXPECT_TRUE(inCellOrder.tetSourceOrder.empty());
    EXPECT_EQ(inCellOrder.values, (std::vector<float>{1, 1, 1, 1, 1, 1, 3}));
}

TEST(Tetrahedralize, BarycentricsReproduceLinearFunctions) {
    const Vec3f a(0.1f, 0.2f, 0.3f), b(1.3f, 0.1f, 0.2f), c(0.4f, 1.1f, 0.0f), d(0.3f, 0.4f, 1.5f);
    ASSERT_GT(signedVolume6(a, b, c, d), 0.f);
    auto f = [](Vec3f p) { return p.x + 2 * p.y - p.z; };
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int i = 0; i < 1000; ++i) {
        float w[4] = {u(rng), u(rng), u(rng), u(rng)};
        const float s = w[0] + w[1] + w[2] + w[3];
        const Vec3f p = (a * w[0] + b * w[1] + c * w[2] + d * w[3]) / s;
        float bary[4];
        ASSERT_TRUE(tetBarycentrics(p, a, b, c, d, bary));
        for (int k = 0; k < 4; ++k) ASSERT_NEAR(bary[k], w[k] / s, 1e-5f);
        EXPECT_NEAR(bary[0] * f(a) + bary[1] * f(b) + bary[2] * f(c) + bary[3] * f(d), f(p), 1e-5f);
    }
    float bary[4];
    EXPECT_FALSE(tetBarycentrics(a, a, b, c, a, bary));  // degenerate
}

TEST(Tetrahedralize, FrameIsTheIdentityExceptAtTheEdgesOfFloat) {
    const auto box = [](Vec3f lo, Vec3f hi) { return Bounds3f{lo, hi}; };
    EXPECT_TRUE(frameForBounds(box(Vec3f(0.f), Vec3f(1.f))).identity());
    EXPECT_TRUE(frameForBounds(box(Vec3f(-1e6f), Vec3f(1e6f))).identity());
    EXPECT_TRUE(frameForBounds(box(Vec3f(1e-6f), Vec3f(2e-6f))).identity());
    EXPECT_TRUE(frameForBounds(Bounds3f{}).identity());
    // Too small and too large: a power of two bringing the diagonal into [1, 2).
    for (const float s : {1e-30f, 1e38f, 1e-40f}) {
        const MeshFrame f = frameForBounds(box(Vec3f(0.f), Vec3f(s)));
        const double diagonal = std::sqrt(3.0) * s * f.scale;
        EXPECT_GE(diagonal, 1.0) << s;
        EXPECT_LT(diagonal, 2.0) << s;
        EXPECT_EQ(std::exp2(std::round(std::log2(f.scale))), f.scale) << s;
        EXPECT_EQ(f.origin, Vec3f(0.f)) << s;
    }
    // Far from the origin on x and z: moved to the centre there, not scaled.
    const MeshFrame far = frameForBounds(box({1e7f, 0.f, -1e7f - 2.f}, {1e7f + 2.f, 1.f, -1e7f}));
    EXPECT_EQ(far.scale, 1.0);
    EXPECT_EQ(far.origin, Vec3f(1e7f + 1.f, 0.f, -1e7f - 1.f));

    // tetrahedralize maps the used points exactly: a tetrahedron scaled by 2^100.
    Mesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {NAN, 0, 0}};
    const std::uint32_t ids[4] = {0, 1, 2, 3};
    m.addCell(CellType::Tetra, ids);
    const ScalarField field{"f", Association::Point, {1, 2, 3, 4, 5}};
    const TetMesh unit = tetrahedralize(m, field);
    EXPECT_TRUE(unit.frame.identity());
    for (Vec3f& p : m.points) p = p * std::ldexp(1.f, 100);
    const TetMesh huge = tetrahedralize(m, field);
    EXPECT_EQ(huge.frame.scale, std::ldexp(1.0, -100));
    for (int i = 0; i < 4; ++i) EXPECT_EQ(huge.points[i], unit.points[i]) << i;
    EXPECT_EQ(huge.bounds.lo, unit.bounds.lo);
    EXPECT_EQ(huge.bounds.hi, unit.bounds.hi);
    EXPECT_DOUBLE_EQ(huge.totalVolume, unit.totalVolume);
}

TEST(Tetrahedralize, TetrahedraOnlyClosesTheGapsOfDroppedCellsAcrossChunks) {
    ProceduralSpec spec;
    spec.targetCells = 60000;  // several chunks of cells
    Mesh m = generateMesh(spec);
    std::vector<std::uint64_t> flat;
    for (std::uint64_t c = 0; c < m.cellCount(); c += 997) {  // a repeated corner: no volume
        m.cellIndices[m.cellOffsets[c] + 1] = m.cellIndices[m.cellOffsets[c]];
        flat.push_back(c);
    }
    const ScalarField f = selectScalarField(m, {});
    const TetMesh t = tetrahedralize(m, f, {.splitCells = false, .spatialOrder = false});
    ASSERT_EQ(t.tets.size(), m.cellCount() - flat.size());
    std::size_t k = 0, next = 0;
    for (std::uint64_t c = 0; c < m.cellCount(); ++c) {
        if (next < flat.size() && flat[next] == c) {
            EXPECT_EQ(t.cellTets[c], 0u);
            ++next;
            continue;
        }
        const auto ids = m.cell(c);
        ASSERT_TRUE(std::equal(ids.begin(), ids.end(), t.tets[k].v)) << "cell " << c;
        ++k;
    }
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// The kernels' layout of the tetrahedra: Morton order (sortCellsSpatially) and blocks with
// 16-bit corner indices (encodeTetBlocks).
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "uvr/core/morton.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {
namespace {

Mesh box(std::uint64_t cells, ProceduralShape shape = ProceduralShape::Box) {
    ProceduralSpec spec;
    spec.shape = shape;
    spec.targetCells = cells;
    spec.fields = {ProceduralField::Jet};
    return generateMesh(spec);
}

/// The mesh with its cells in a random order (a file whose cells are not numbered in space).
Mesh shuffled(const Mesh& m, std::uint64_t seed) {
    std::vector<std::uint64_t> order(m.cellCount());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937_64(seed));
    Mesh out;
    out.points = m.points;
    for (std::uint64_t c : order) out.addCell(m.cellTypes[c], m.cell(c));
    out.fields = m.fields;
    return out;
}

TEST(TetBlocks, CornersDecodeToTheirPointsAndValues) {
    const Mesh m = box(60000);  // several blocks
    const TetMesh t = tetrahedralize(m, selectScalarField(m, {}));
    const std::uint64_t n = t.tets.size();
    const std::uint64_t blocks = (n + kTetBlockSize - 1) / kTetBlockSize;
    ASSERT_GE(blocks, 5u);
    ASSERT_EQ(t.tetCorners.size(), n);
    ASSERT_EQ(t.blockVertexBase.size(), blocks + 1);
    ASSERT_EQ(t.blockVertices.size(), t.blockVertexBase.back());
    const TetMeshView v = t.view();
    for (std::uint64_t i = 0; i < n; ++i) {
        BlockVertex x[4];
        v.tetVertices(i, x);
        for (int k = 0; k < 4; ++k) {
            const std::uint32_t b = static_cast<std::uint32_t>(i >> kTetBlockBits);
            ASSERT_LT(t.tetCorners[i].v[k], t.blockVertexBase[b + 1] - t.blockVertexBase[b]);
            ASSERT_TRUE(x[k].p == t.points[t.tets[i].v[k]]) << "tetrahedron " << i;
            ASSERT_EQ(x[k].value, t.values[t.tets[i].v[k]]) << "tetrahedron " << i;
        }
    }
    // A block lists each of its points once.
    for (std::uint64_t b = 0; b < blocks; ++b) {
        std::vector<std::uint32_t> ids(t.blockVertexPoint.begin() + t.blockVertexBase[b],
                                       t.blockVertexPoint.begin() + t.blockVertexBase[b + 1]);
        std::sort(ids.begin(), ids.end());
        EXPECT_EQ(std::adjacent_find(ids.begin(), ids.end()), ids.end()) << "block " << b;
    }
}

TEST(TetBlocks, NewValuesReachTheBlocks) {
    const Mesh m = box(20000);
    TetMesh t = tetrahedralize(m, selectScalarField(m, {}));
    std::vector<float> values(m.pointCount());
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = float(i % 97);
    assignTetValues(t, ScalarField{"i", Association::Point, values});
    for (std::size_t i = 0; i < t.blockVertices.size(); ++i)
        ASSERT_EQ(t.blockVertices[i].value, values[t.blockVertexPoint[i]]);
    // Cell data leaves the blocks' values at 0 (kernels read the cells' own values).
    assignTetValues(t, ScalarField{"c", Association::Cell, std::vector<float>(m.cellCount(), 5.f)});
    for (const BlockVertex& x : t.blockVertices) ASSERT_EQ(x.value, 0.f);
}

TEST(TetBlocks, MortonOrderPermutesTheCellsAndCellDataFollows) {
    // A graded mesh: its Morton keys crowd into a corner, so the sort takes several radix passes.
    const Mesh m = box(300000, ProceduralShape::Graded);
    std::vector<float> cellValues(m.cellCount());
    for (std::size_t c = 0; c < cellValues.size(); ++c) cellValues[c] = float(c);
    const ScalarField field{"id", Association::Cell, cellValues};
    const TetMesh sorted = tetrahedralize(m, field);
    const TetMesh unsorted = tetrahedralize(m, field, {.spatialOrder = false});
    const std::uint64_t n = sorted.tets.size();
    ASSERT_EQ(unsorted.tets.size(), n);
    ASSERT_EQ(sorted.tetSourceOrder.size(), n);
    std::vector<bool> seen(n, false);
    std::uint64_t previous = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint32_t from = sorted.tetSourceOrder[i];
        ASSERT_LT(from, n);
        ASSERT_FALSE(seen[from]) << "tetrahedron " << from << " twice";
        seen[from] = true;
        for (int k = 0; k < 4; ++k) ASSERT_EQ(sorted.tets[i].v[k], unsorted.tets[from].v[k]);
        ASSERT_EQ(sorted.values[i], unsorted.values[from]);
        Vec3f c(0.f);
        for (int k = 0; k < 4; ++k) c += sorted.points[sorted.tets[i].v[k]];
        const std::uint64_t key = morton63(c * 0.25f, sorted.bounds);
        ASSERT_GE(key, previous) << "tetrahedron " << i << " out of Morton order";
        previous = key;
    }
}

TEST(TetBlocks, SpatialOrderKeepsBlocksCompact) {
    // Cells numbered at random: unsorted, every block spans the whole mesh.
    const Mesh m = shuffled(box(100000), 5);
    const ScalarField field = selectScalarField(m, {});
    const TetMesh sorted = tetrahedralize(m, field);
    const TetMesh unsorted = tetrahedralize(m, field, {.spatialOrder = false});
    const double perTetSorted = double(sorted.blockVertices.size()) / sorted.tets.size();
    const double perTetUnsorted = double(unsorted.blockVertices.size()) / unsorted.tets.size();
    EXPECT_LT(perTetSorted, 0.35) << "block vertices per tetrahedron";  // about 1/6 inside
    EXPECT_GT(perTetUnsorted, 2.0 * perTetSorted);
}

TEST(TetBlocks, NativeCellsKeepTheirSourceCells) {
    const Mesh m = generateMixedCellMesh(12, 0.1f, 3);
    const TetMesh t = tetrahedralize(m, selectScalarField(m, {}));
    ASSERT_GT(t.hexCount, 1u);
    const TetMeshView v = t.view();
    for (std::uint64_t j = 0; j < t.nativeSource.size(); ++j) {
        std::uint32_t ids[kMaxCellCorners];
        const int n = v.corners(t.tets.size() + j, ids);
        const auto source = m.cell(t.nativeSource[j]);
        ASSERT_EQ(std::size_t(n), source.size());
        for (int k = 0; k < n; ++k) ASSERT_EQ(ids[k], source[k]) << "native cell " << j;
    }
}

}  // namespace
}  // namespace uvr

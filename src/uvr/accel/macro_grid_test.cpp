// SPDX-License-Identifier: MIT
// Macrocell grids against brute force: every tetrahedron's values lie in the range of every
// macrocell its box overlaps, macrocells no tetrahedron overlaps are empty, the boundary's
// macrocells and a cell-centred field's have an infinite gradient spread, and a ray leaves a
// macrocell where gridCellExit says.
#include "uvr/accel/macro_grid.h"

#include <gtest/gtest.h>

#include <random>

#include "test_meshes.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

/// A procedural mesh of about `cells` tetrahedra (the shell is non-convex, with a hole: empty
/// macrocells exist there).
PreparedMesh preparedProcedural(ProceduralShape shape, ProceduralField field, std::uint64_t cells) {
    ProceduralSpec spec;
    spec.shape = shape;
    spec.targetCells = cells;
    spec.fields = {field};
    const Mesh mesh = generateMesh(spec);
    PrepareOptions o;
    o.kd.leafCells = 4096;
    return prepareMesh(mesh, selectScalarField(mesh, {}), o);
}

void checkAgainstBruteForce(const PreparedMesh& pm, int& empty, int& inner, int& edge) {
    ASSERT_TRUE(pm.kd && pm.macro);
    const KdPartitions& kd = *pm.kd;
    const MacroGrids& mg = *pm.macro;
    ASSERT_EQ(mg.grids.size(), kd.partitions.size());
    std::vector<char> touched(mg.cells.size(), 0), boundary(mg.cells.size(), 0);
    for (std::uint32_t p = 0; p < kd.partitions.size(); ++p) {
        const KdPartition& part = kd.partitions[p];
        const PartitionGrid& g = mg.grids[p];
        for (std::uint32_t i = 0; i < part.cellCount; ++i) {
            const std::uint32_t t = kd.cells[part.firstCell + i];
            const Tet& tet = pm.tets.tets[t];
            Bounds3f box;
            for (int k = 0; k < 4; ++k) box.extend(pm.tets.points[tet.v[k]]);
            bool onBoundary = false;
            for (int f = 0; f < 4; ++f) onBoundary |= pm.neighbors[4 * t + f] == kNoTet;
            std::uint32_t a[3], b[3];
            macroCellOf(g, box.lo, a);
            macroCellOf(g, box.hi, b);
            for (std::uint32_t z = a[2]; z <= b[2]; ++z)
                for (std::uint32_t y = a[1]; y <= b[1]; ++y)
                    for (std::uint32_t x = a[0]; x <= b[0]; ++x) {
                        const std::size_t c = g.first + (z * g.dims[1] + y) * g.dims[0] + x;
                        touched[c] = 1;
                        boundary[c] |= onBoundary;
                        for (int k = 0; k < 4; ++k) {
                            const float v = pm.tets.values[tet.v[k]];
                            ASSERT_GE(v, mg.cells[c].valueMin) << "partition " << p;
                            ASSERT_LE(v, mg.cells[c].valueMax) << "partition " << p;
                        }
                    }
        }
    }
    empty = inner = edge = 0;
    for (std::size_t c = 0; c < mg.cells.size(); ++c) {
        EXPECT_EQ(mg.cells[c].empty(), !touched[c]) << c;
        empty += !touched[c];
        if (!touched[c]) continue;
        // Boundary or not, a point field's spread is bounded; the boundary is flagged.
        EXPECT_LT(mg.cells[c].gradientSpread, INFINITY) << c;
        EXPECT_EQ(mg.cells[c].atBoundary, boundary[c] ? 1u : 0u) << c;
        ++(boundary[c] ? edge : inner);
    }
    EXPECT_GT(mg.cells.size(), kd.partitions.size() * 16);  // finer than the partitions
}

TEST(MacroGrid, RangesHoldEveryOverlappingCellAndEmptyCellsHoldNone) {
    int empty, inner, edge;
    checkAgainstBruteForce(preparedProcedural(ProceduralShape::Box, ProceduralField::Jet, 60000),
                           empty, inner, edge);
    EXPECT_GT(inner, 0);
    EXPECT_GT(edge, 0);
    checkAgainstBruteForce(preparedProcedural(ProceduralShape::Shell, ProceduralField::Jet, 60000),
                           empty, inner, edge);
    EXPECT_GT(empty, 0);  // the shell's hole
    EXPECT_GT(edge, 0);
}

TEST(MacroGrid, LinearFieldHasNoSpreadInsideAndCellDataHasNoBound) {
    const PreparedMesh linear =
        preparedProcedural(ProceduralShape::Box, ProceduralField::Linear, 60000);
    int inner = 0;
    int edge = 0;
    for (const MacroCell& c : linear.macro->cells)
        if (!c.empty()) {
            EXPECT_LT(c.gradientSpread, 1e-3f);  // at the boundary too
            ++(c.atBoundary ? edge : inner);
        }
    EXPECT_GT(inner, 0);
    EXPECT_GT(edge, 0);
    // A cell-centred field: no gradient bound anywhere (its jumps are not bounded).
    Mesh m = testing::makeHexGrid(4, 0.f, 1.f, [](Vec3f p) { return p.x; });
    Field f{"id", Association::Cell, 1, {}};
    for (std::uint64_t i = 0; i < m.cellCount(); ++i) f.values.push_back(float(i));
    m.fields.push_back(f);
    FieldSpec spec;
    spec.name = "id";
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, spec));
    for (const MacroCell& c : pm.macro->cells)
        if (!c.empty()) {
            EXPECT_EQ(c.gradientSpread, INFINITY);
        }
}

TEST(MacroGrid, RaysLeaveACellWhereGridCellExitSays) {
    PartitionGrid g =
        layoutPartitionGrid(Bounds3f{Vec3f(-1.f, 0.f, 2.f), Vec3f(3.f, 1.f, 2.5f)}, 64);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f), d(-1.f, 1.f);
    int inner = 0;
    for (int i = 0; i < 2000; ++i) {
        const Vec3f org(-1.f + 4.f * u(rng), u(rng), 2.f + 0.5f * u(rng));
        Vec3f dir(d(rng), d(rng), d(rng));
        if (i % 7 == 0) dir.y = 0.f;  // parallel to a family of faces
        dir = normalize(dir);
        const Vec3f inv(1.f / dir.x, 1.f / dir.y, 1.f / dir.z);
        std::uint32_t idx[3], after[3], before[3];
        const std::uint32_t c = macroCellOf(g, org, idx);
        const float t = gridCellExit(g, idx, org, inv);
        ASSERT_GE(t, 0.f);
        // Leaving through the grid's outer face, starting on a face (rounding decides), or
        // grazing a face far outside the grid (the outer cells reach to infinity).
        if (t == INFINITY || t < 1e-3f || t > 5.f) continue;
        ++inner;
        EXPECT_EQ(macroCellOf(g, org + dir * (t - 1e-4f), before), c) << i;
        EXPECT_NE(macroCellOf(g, org + dir * (t + 1e-4f), after), c) << i;
    }
    EXPECT_GT(inner, 500);
}

}  // namespace
}  // namespace uvr

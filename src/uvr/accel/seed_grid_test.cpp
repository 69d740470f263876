// SPDX-License-Identifier: MIT
#include "uvr/accel/seed_grid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <random>

#include "uvr/accel/point_locator.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

PreparedMesh preparedShell(std::uint32_t leafCells) {
    ProceduralSpec spec;
    spec.shape = ProceduralShape::Shell;  // non-convex, with a hole: empty grid cells exist
    spec.targetCells = 20000;
    spec.fields = {ProceduralField::Linear};
    const Mesh mesh = generateMesh(spec);
    PrepareOptions o;
    o.kd.leafCells = leafCells;
    return prepareMesh(mesh, selectScalarField(mesh, {}), o);
}

bool tetHolds(const TetLocator& loc, std::uint32_t t, Vec3f p) {
    float bary[4];
    return loc.inside(t, p, bary);
}

// Brute force: every point of a partition's box either has a seed, or lies in none of the
// partition's cells; and walking from the seed finds a cell containing the point when one does.
TEST(SeedGrid, EmptyCellsHoldNoTetrahedronAndSeedsLeadToThePoint) {
    const PreparedMesh pm = preparedShell(512);
    ASSERT_TRUE(pm.kd && pm.seeds);
    const KdPartitions& kd = *pm.kd;
    ASSERT_GT(kd.partitions.size(), 8u);
    const SeedGridView seeds = pm.seeds->view();
    const TetLocator loc = pm.locator();
    std::mt19937 rng(7);
    int withCell = 0, empty = 0, walked = 0;
    for (std::uint32_t p = 0; p < kd.partitions.size(); ++p) {
        const KdPartition& part = kd.partitions[p];
        std::uniform_real_distribution<float> u(0.f, 1.f);
        for (int i = 0; i < 200; ++i) {
            const Vec3f e = part.box.extent();
            const Vec3f x(part.box.lo.x + u(rng) * e.x, part.box.lo.y + u(rng) * e.y,
                          part.box.lo.z + u(rng) * e.z);
            std::uint32_t truth = kNoTet;
            for (std::uint32_t k = 0; k < part.cellCount && truth == kNoTet; ++k)
                if (tetHolds(loc, kd.cells[part.firstCell + k], x))
                    truth = kd.cells[part.firstCell + k];
            const std::uint32_t s = seeds.seed(p, x);
            if (truth == kNoTet) {
                ++empty;
                continue;
            }
            ++withCell;
            ASSERT_NE(s, kNoTet) << "partition " << p << ": a cell contains the point";
            LocateCounters c;
            float bary[4];
            const std::uint32_t found = loc.locateIn(pm.cellTree.view(), 0, x, s, bary, c);
            ASSERT_NE(found, kNoTet);
            EXPECT_TRUE(tetHolds(loc, found, x));
            walked += c.bvhQueries == 0;
        }
    }
    EXPECT_GT(withCell, 1000);
    EXPECT_GT(empty, 100);  // the shell's hole and outside
    // Seeds are close: nearly every location succeeds by walking, without the BVH.
    EXPECT_GT(walked, withCell * 95 / 100);
}

TEST(SeedGrid, CentreSeedsContainTheirCentre) {
    const PreparedMesh pm = preparedShell(2048);
    const SeedGrids& sg = *pm.seeds;
    const TetLocator loc = pm.locator();
    int checked = 0;
    for (std::size_t p = 0; p < sg.grids.size(); ++p) {
        const PartitionGrid& g = sg.grids[p];
        for (std::uint32_t z = 0; z < g.dims[2]; ++z)
            for (std::uint32_t y = 0; y < g.dims[1]; ++y)
                for (std::uint32_t x = 0; x < g.dims[0]; ++x) {
                    const Vec3f c(g.lo.x + (x + 0.5f) / g.cellsPerUnit.x,
                                  g.lo.y + (y + 0.5f) / g.cellsPerUnit.y,
                                  g.lo.z + (z + 0.5f) / g.cellsPerUnit.z);
                    const std::uint32_t s = sg.seeds[g.first + (z * g.dims[1] + y) * g.dims[0] + x];
                    // A centre inside some cell of the partition gets a seed containing it.
                    const KdPartition& part = pm.kd->partitions[p];
                    bool inAny = false;
                    for (std::uint32_t k = 0; k < part.cellCount && !inAny; ++k)
                        inAny = tetHolds(loc, pm.kd->cells[part.firstCell + k], c);
                    if (!inAny) continue;
                    ++checked;
                    ASSERT_NE(s, kNoTet);
                    EXPECT_TRUE(tetHolds(loc, s, c)) << "partition " << p;
                }
    }
    EXPECT_GT(checked, 500);
    // About kTetsPerSeedCell tetrahedra per grid cell (at most twice the target cell count).
    EXPECT_LE(double(sg.seeds.size()),
              2.0 * pm.kd->cells.size() / kTetsPerSeedCell + 8.0 * sg.grids.size());
}

TEST(SeedGrid, SameResultWhateverTheThreadCount) {
    const PreparedMesh pm = preparedShell(256);
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const SeedGrids one = buildSeedGrids(pm.tets, *pm.kd);
    omp_set_num_threads(2);
    const SeedGrids two = buildSeedGrids(pm.tets, *pm.kd);
    omp_set_num_threads(threads);
    EXPECT_EQ(one.seeds, two.seeds);
    ASSERT_EQ(one.grids.size(), two.grids.size());
    for (std::size_t i = 0; i < one.grids.size(); ++i)
        EXPECT_EQ(one.grids[i].first, two.grids[i].first);
}

TEST(SeedGrid, FlatAndEmptyPartitionsGetValidGrids) {
    // A single flat layer of cells: the partition boxes have (almost) no depth.
    TetMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1e-7f}};
    mesh.tets = {Tet{{0, 1, 2, 3}}};
    mesh.values = {0, 1, 2, 3};
    mesh.bounds.extend(Vec3f(0, 0, 0));
    mesh.bounds.extend(Vec3f(1, 1, 1e-7f));
    encodeTetBlocks(mesh);
    const KdPartitions kd = buildKdPartitions(mesh);
    const SeedGrids sg = buildSeedGrids(mesh, kd);
    ASSERT_EQ(sg.grids.size(), kd.partitions.size());
    for (const PartitionGrid& g : sg.grids)
        for (std::uint32_t d : g.dims) EXPECT_GE(d, 1u);
    EXPECT_EQ(sg.view().seed(0, Vec3f(0.1f, 0.1f, 0.f)), 0u);
    const std::uint32_t nanSeed = sg.view().seed(0, Vec3f(NAN, 0.1f, 0.f));  // clamped, no crash
    EXPECT_TRUE(nanSeed == kNoTet || nanSeed < mesh.tets.size());
}

}  // namespace
}  // namespace uvr

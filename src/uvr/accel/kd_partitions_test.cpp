// SPDX-License-Identifier: MIT
#include "uvr/accel/kd_partitions.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "test_meshes.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

PreparedMesh splitGrid(std::uint32_t leafCells) {
    const Mesh m = testing::jitteredHexGrid(8);
    PrepareOptions o;
    o.kd.leafCells = leafCells;
    o.cells.splitCells = true;  // the tests below check the tetrahedra's lists
    return prepareMesh(m, selectScalarField(m, {}), o);
}

/// The leaf whose (closed) region contains p, descending below-first on ties; and its region.
std::uint32_t leafOf(const KdPartitions& kd, Vec3f p, Bounds3f* region = nullptr) {
    Bounds3f r = kd.bounds;
    std::uint32_t node = 0;
    while (!kd.nodes[node].isLeaf()) {
        const KdNode n = kd.nodes[node];
        const bool below = p[n.axis()] <= n.split;
        (below ? r.hi : r.lo)[n.axis()] = n.split;
        node = n.child() + (below ? 0u : 1u);
    }
    if (region) *region = r;
    return kd.nodes[node].child();
}

TEST(KdPartitions, EveryCellInAPartitionWithItsValuesInRange) {
    const PreparedMesh pm = splitGrid(64);
    const KdPartitions& kd = *pm.kd;
    ASSERT_GT(kd.partitions.size(), 20u);
    std::vector<int> seen(pm.tets.tets.size(), 0);
    for (const KdPartition& p : kd.partitions) {
        for (std::uint32_t i = 0; i < p.cellCount; ++i) {
            const std::uint32_t t = kd.cells[p.firstCell + i];
            ++seen[t];
            for (std::uint32_t v : pm.tets.tets[t].v) {
                EXPECT_GE(pm.tets.values[v], p.valueMin);
                EXPECT_LE(pm.tets.values[v], p.valueMax);
            }
        }
    }
    for (int s : seen) ASSERT_GE(s, 1);
    EXPECT_GE(kd.duplicationFactor(pm.tets.tets.size()), 1.0);
    EXPECT_LT(kd.duplicationFactor(pm.tets.tets.size()), 8.0);  // tiny leaves of big cells
}

TEST(KdPartitions, APointsCellIsInThePartitionWhoseRegionHoldsIt) {
    const PreparedMesh pm = splitGrid(32);
    const KdPartitions& kd = *pm.kd;
    const TetLocator loc = pm.locator();
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    int found = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3f p(u(rng), u(rng), u(rng));
        LocateCounters c;
        float bary[4];
        const std::uint32_t t = loc.locate(p, kNoTet, bary, c);
        if (t == kNoTet) continue;
        ++found;
        const KdPartition& part = kd.partitions[leafOf(kd, p)];
        ASSERT_TRUE(part.box.contains(p));
        // The cell holding the point is one of the partition's cells.
        const auto first = kd.cells.begin() + part.firstCell;
        ASSERT_NE(std::find(first, first + part.cellCount, t), first + part.cellCount)
            << "cell " << t << " holds the point but is not in its partition";
    }
    EXPECT_GT(found, 3000);
}

TEST(KdPartitions, TraversalVisitsExactlyTheCrossedLeavesInOrder) {
    const PreparedMesh pm = splitGrid(16);
    const KdPartitions& kd = *pm.kd;
    const KdView view = kd.view();
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.5f, 1.5f);
    std::vector<Ray> rays;
    for (int i = 0; i < 500; ++i) {
        const Vec3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
        rays.push_back({a * 2.f, normalize(b - a * 2.f)});
    }
    // Grazing rays: along axes, exactly on split planes of the root and its children.
    for (std::uint32_t n = 0; n < std::min<std::size_t>(kd.nodes.size(), 15); ++n) {
        if (kd.nodes[n].isLeaf()) continue;
        Vec3f o(0.1f, -0.2f, 0.05f);
        o[kd.nodes[n].axis()] = kd.nodes[n].split;
        for (int a = 0; a < 3; ++a) {
            Vec3f d(0.f, 0.f, 0.f), start = o;
            d[a] = 1.f;
            start[a] = -3.f;
            rays.push_back({start, d});
        }
    }
    for (const Ray& ray : rays) {
        const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
        float t0 = 0.f, t1 = INFINITY;
        if (!intersectBox(kd.bounds, ray.org, inv, t0, t1)) continue;
        std::vector<std::pair<float, float>> pieces;
        std::vector<std::uint32_t> leaves;
        kdTraverse(view, ray, inv, t0, t1, [&](std::uint32_t leaf, float a, float b) {
            pieces.push_back({a, b});
            leaves.push_back(leaf);
            return false;
        });
        ASSERT_FALSE(pieces.empty());
        EXPECT_EQ(pieces.front().first, t0);
        EXPECT_EQ(pieces.back().second, t1);
        for (size_t i = 0; i < pieces.size(); ++i) {
            ASSERT_LE(pieces[i].first, pieces[i].second);
            if (i > 0) {
                ASSERT_EQ(pieces[i].first, pieces[i - 1].second);  // no gap, no overlap
            }
            // The middle of each piece lies in its leaf's region.
            if (pieces[i].second - pieces[i].first > 1e-4f) {
                const Vec3f mid = ray.at(0.5f * (pieces[i].first + pieces[i].second));
                Bounds3f region;
                leafOf(kd, mid, &region);
                Bounds3f grown = region;
                grown.lo = grown.lo - Vec3f(1e-5f);
                grown.hi = grown.hi + Vec3f(1e-5f);
                // Ties on a plane may resolve to either side: accept the neighbour's region.
                EXPECT_TRUE(leafOf(kd, mid) == leaves[i] || grown.contains(mid));
            }
        }
        std::vector<std::uint32_t> sorted = leaves;
        std::sort(sorted.begin(), sorted.end());
        EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end())
            << "a leaf visited twice";
        // Brute force: dense points along the ray each lie in a visited leaf.
        for (int k = 0; k <= 400; ++k) {
            const float t = t0 + (t1 - t0) * k / 400.f;
            const std::uint32_t leaf = leafOf(kd, ray.at(t));
            const bool visited = std::find(leaves.begin(), leaves.end(), leaf) != leaves.end();
            const bool onPlane = [&] {  // points on a split plane belong to both sides
                for (const KdNode& n : kd.nodes)
                    if (!n.isLeaf() && ray.at(t)[n.axis()] == n.split) return true;
                return false;
            }();
            ASSERT_TRUE(visited || onPlane) << "leaf " << leaf << " crossed but not visited";
        }
    }
}

TEST(KdPartitions, SmallLeavesGiveMorePartitions) {
    EXPECT_GT(splitGrid(16).kd->partitions.size(), splitGrid(256).kd->partitions.size());
    const PreparedMesh one = splitGrid(1u << 20);
    EXPECT_EQ(one.kd->partitions.size(), 1u);
    EXPECT_EQ(one.kd->cells.size(), one.tets.tets.size());
}

}  // namespace
}  // namespace uvr

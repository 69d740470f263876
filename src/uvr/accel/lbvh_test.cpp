// SPDX-License-Identifier: MIT
#include "uvr/accel/lbvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "test_meshes.h"
#include "uvr/accel/point_locator.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

PreparedMesh preparedTets(const Mesh& m, bool lbvh, bool partitions = false) {
    PrepareOptions o;
    o.partitions = partitions;
    o.kd.leafCells = 128;
    o.cells.splitCells = true;  // the tests below check trees over the tetrahedra
    if (lbvh) o.lbvh = buildLbvhCpu;
    return prepareMesh(m, selectScalarField(m, {}), o);
}

/// Walks the tree at `root`: every primitive position reached once, leaves of at most leafSize
/// primitives with boxes equal to the union of their tetrahedra, inner boxes equal to the union
/// of their children, depth within kBvhMaxDepth. Returns the positions reached, in leaf order.
std::vector<std::uint32_t> checkTree(const TetMesh& mesh, const std::vector<BvhNode>& nodes,
                                     const std::vector<std::uint32_t>& prims, std::uint32_t root,
                                     int leafSize) {
    std::vector<std::uint32_t> reached;
    std::vector<std::pair<std::uint32_t, int>> stack{{root, 1}};
    while (!stack.empty()) {
        auto [n, depth] = stack.back();
        stack.pop_back();
        EXPECT_LE(depth, kBvhMaxDepth);
        const BvhNode& node = nodes.at(n);
        Bounds3f expected;
        if (node.count > 0) {
            EXPECT_LE(node.count, static_cast<std::uint32_t>(leafSize));
            for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
                reached.push_back(k);
                expected.extend(tetBounds(mesh.points.data(), mesh.tets[prims.at(k)]));
            }
        } else {
            for (std::uint32_t c : {node.first, node.first + 1}) {
                expected.extend(nodes.at(c).box);
                stack.push_back({c, depth + 1});
            }
        }
        EXPECT_TRUE(node.box.lo == expected.lo && node.box.hi == expected.hi) << "node " << n;
    }
    std::sort(reached.begin(), reached.end());
    return reached;
}

TEST(Lbvh, MortonCodesInterleaveTheAxesAndClamp) {
    Bounds3f b;
    b.lo = Vec3f(0.f);
    b.hi = Vec3f(kMortonGrid);  // one unit per grid cell
    EXPECT_EQ(morton63(Vec3f(0.f), b), 0u);
    EXPECT_EQ(morton63(Vec3f(kMortonGrid - 0.5f), b), 0x7fffffffffffffffull);
    EXPECT_EQ(morton63(Vec3f(1.5f, 0.f, 0.f), b), 4u);  // x is the most significant of each triple
    EXPECT_EQ(morton63(Vec3f(0.f, 1.5f, 0.f), b), 2u);
    EXPECT_EQ(morton63(Vec3f(0.f, 0.f, 1.5f), b), 1u);
    EXPECT_EQ(morton63(Vec3f(2.f, 0.f, 0.f), b), 32u);
    EXPECT_EQ(morton63(Vec3f(3.f, 1.f, 2.f), b), 32u + 4u + 2u + 8u);
    EXPECT_EQ(morton63(Vec3f(-5.f, 5e7f, NAN), b), morton63(Vec3f(0.f, kMortonGrid, 0.f), b));
    Bounds3f flat = b;
    flat.hi.z = 0.f;  // a flat axis quantises to 0
    EXPECT_EQ(morton63(Vec3f(0.f, 0.f, 7.f), flat), 0u);
}

TEST(Lbvh, InnerNodesAreTheRadixTreeOfTheKeys) {
    // Sorted keys with many duplicates: each inner node's range must be maximal for its common
    // prefix and split where that prefix's next bit changes (Karras 2012, Sec. 3).
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::uint64_t> key(0, 40);
    for (int trial = 0; trial < 20; ++trial) {
        const std::int64_t m = 2 + trial * 13;
        std::vector<std::uint64_t> keys(m);
        for (auto& k : keys) k = key(rng);
        std::sort(keys.begin(), keys.end());
        auto delta = [&](std::int64_t i, std::int64_t j) {
            return lbvhDelta(keys.data(), m, i, j);
        };
        std::vector<int> covered(m - 1 + m, 0);  // inner nodes, then leaves
        covered[0] = 1;                          // the root is node 0
        for (std::int64_t i = 0; i + 1 < m; ++i) {
            const LbvhInner r = lbvhInnerNode(keys.data(), m, i);
            ASSERT_TRUE(r.first == i || r.last == i) << "trial " << trial << " node " << i;
            ASSERT_LE(r.first, r.split);
            ASSERT_LT(r.split, r.last);
            int prefix = 96;  // common prefix of the whole range
            for (std::int64_t k = r.first; k < r.last; ++k)
                prefix = std::min(prefix, delta(k, k + 1));
            EXPECT_EQ(delta(r.first, r.last), prefix);
            EXPECT_LT(delta(r.first, r.first - 1), prefix);  // maximal on both sides
            EXPECT_LT(delta(r.last, r.last + 1), prefix);
            EXPECT_EQ(delta(r.split, r.split + 1), prefix);  // the prefix's next bit changes here
            ++covered[r.first == r.split ? m - 1 + r.split : r.split];
            ++covered[r.last == r.split + 1 ? m - 1 + r.split + 1 : r.split + 1];
        }
        for (int c : covered) ASSERT_EQ(c, 1) << "trial " << trial;  // a tree: one parent each
    }
}

TEST(Lbvh, MeshTreeHoldsEveryTetrahedronOnceInExactNestedBoxes) {
    const PreparedMesh pm = preparedTets(testing::jitteredHexGrid(9), /*lbvh=*/true);
    const Bvh& bvh = pm.bvh;
    const std::size_t n = pm.tets.tets.size();
    EXPECT_EQ(bvh.nodes.size() % 2, 1u);                 // 2 K + 1
    EXPECT_GE(bvh.nodes.size(), 2 * ((n + 3) / 4) - 1);  // leaves of at most 4
    EXPECT_LE(bvh.nodes.size(), 2 * n - 1);
    const std::vector<std::uint32_t> reached = checkTree(pm.tets, bvh.nodes, bvh.primIds, 0, 4);
    ASSERT_EQ(reached.size(), n);
    for (std::size_t k = 0; k < n; ++k) ASSERT_EQ(reached[k], k);
    std::vector<std::uint32_t> ids = bvh.primIds;
    std::sort(ids.begin(), ids.end());
    for (std::size_t k = 0; k < n; ++k) ASSERT_EQ(ids[k], k);  // a permutation of the tets
}

TEST(Lbvh, PointQueriesFindExactlyTheContainingTetrahedra) {
    const PreparedMesh pm = preparedTets(testing::jitteredHexGrid(7), /*lbvh=*/true);
    const TetLocator loc = pm.locator();
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.1f, 1.1f);
    for (int q = 0; q < 2000; ++q) {
        const Vec3f p(u(rng), u(rng), u(rng));
        std::vector<std::uint32_t> brute, found;
        float bary[4];
        for (std::uint32_t t = 0; t < pm.tets.tets.size(); ++t)
            if (loc.inside(t, p, bary)) brute.push_back(t);
        bvhVisitPoint(pm.bvh.view(), p, [&](std::uint32_t t) {
            if (loc.inside(t, p, bary)) found.push_back(t);
            return false;
        });
        std::sort(found.begin(), found.end());
        ASSERT_EQ(found, brute) << "point " << p.x << "," << p.y << "," << p.z;
    }
}

TEST(Lbvh, CoincidentCentresGiveABalancedTree) {
    // 5000 copies of one tetrahedron: every key equal, so the index decides (depth ~ log2 n).
    TetMesh mesh;
    mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    mesh.tets.assign(5000, Tet{{0, 1, 2, 3}});
    mesh.values.assign(4, 0.f);
    mesh.bounds.extend(Vec3f(0.f));
    mesh.bounds.extend(Vec3f(1.f));
    const Bvh bvh = buildMeshLbvh(mesh, buildLbvhCpu, 4);
    EXPECT_EQ(checkTree(mesh, bvh.nodes, bvh.primIds, 0, 4).size(), 5000u);
    int depth = 0;
    for (std::uint32_t n = 0; bvh.nodes[n].count == 0; n = bvh.nodes[n].first) ++depth;
    EXPECT_LE(depth, 12);  // ceil(log2(1250)) = 11
}

TEST(Lbvh, SegmentsGetTheirOwnTreesIncludingEmptyAndSingleLeafOnes) {
    const Mesh m = testing::jitteredHexGrid(5);
    const TetMesh mesh = tetrahedralize(m, selectScalarField(m, {}), {.splitCells = true});
    const std::uint32_t n = static_cast<std::uint32_t>(mesh.tets.size());
    // Segments: all tets reversed, nothing, three tets, the first half again.
    std::vector<std::uint32_t> ids;
    for (std::uint32_t t = n; t-- > 0;) ids.push_back(t);
    ids.insert(ids.end(), {7, 3, 5});
    for (std::uint32_t t = 0; t < n / 2; ++t) ids.push_back(t);
    LbvhInput in;
    in.mesh = &mesh;
    in.tetIds = ids;
    in.segmentBegin = {0, n, n, n + 3, ids.size()};
    in.segmentBounds = {mesh.bounds, mesh.bounds, mesh.bounds, mesh.bounds};
    in.leafSize = 8;
    const LbvhResult r = buildLbvhCpu(in);
    ASSERT_EQ(r.roots.size(), 4u);
    std::vector<std::uint32_t> tetOf(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) tetOf[k] = ids[r.order[k]];
    const std::vector<std::uint32_t> segments[] = {checkTree(mesh, r.nodes, tetOf, r.roots[0], 8),
                                                   {},
                                                   checkTree(mesh, r.nodes, tetOf, r.roots[2], 8),
                                                   checkTree(mesh, r.nodes, tetOf, r.roots[3], 8)};
    EXPECT_EQ(r.roots[1], r.roots[2]);         // the empty segment has no nodes
    EXPECT_EQ(r.nodes[r.roots[2]].count, 3u);  // three tets: one leaf
    for (int s : {0, 2, 3}) {
        ASSERT_EQ(segments[s].size(), in.segmentBegin[s + 1] - in.segmentBegin[s]) << s;
        for (std::size_t k = 0; k < segments[s].size(); ++k) {
            ASSERT_EQ(segments[s][k], in.segmentBegin[s] + k);  // its own positions only
            ASSERT_GE(r.order[segments[s][k]], in.segmentBegin[s]);
            ASSERT_LT(r.order[segments[s][k]], in.segmentBegin[s + 1]);
        }
    }
}

TEST(Lbvh, BadSegmentsAreRefused) {
    const Mesh m = testing::jitteredHexGrid(2);
    const TetMesh mesh = tetrahedralize(m, selectScalarField(m, {}), {.splitCells = true});
    LbvhInput in;
    in.mesh = &mesh;
    in.segmentBegin = {0, mesh.tets.size() - 1};  // one short
    in.segmentBounds = {mesh.bounds};
    EXPECT_THROW(buildLbvhCpu(in), Error);
    in.segmentBegin = {0, mesh.tets.size()};
    in.leafSize = 0;
    EXPECT_THROW(buildLbvhCpu(in), Error);
    in.leafSize = 4;
    const LbvhResult r = buildLbvhCpu(in);
    EXPECT_FALSE(r.nodes.empty());
}

TEST(Lbvh, EmptyMeshGivesAnEmptyTree) {
    TetMesh mesh;
    const Bvh bvh = buildMeshLbvh(mesh, buildLbvhCpu);
    EXPECT_TRUE(bvh.nodes.empty());
    EXPECT_TRUE(bvh.primIds.empty());
}

TEST(Lbvh, RendersMatchThoseWithSahTrees) {
    // Same mesh, same partitions, only the BVHs differ: a sample on a face shared by two cells may
    // resolve to either, so images agree to rounding.
    const Mesh m = testing::jitteredHexGrid(10);
    for (const bool partitions : {false, true}) {
        const PreparedMesh sah = preparedTets(m, false, partitions);
        const PreparedMesh lbvh = preparedTets(m, true, partitions);
        RenderSettings s;
        s.width = 96;
        s.height = 80;
        s.method = partitions ? RenderMethod::Partitions : RenderMethod::Reference;
        s.tf = transferFunctionPreset("cool-to-warm");
        applyOpacitySpec(s.tf, "0:0,1:0.5");
        s.camera = orbitCamera(resetCamera(sah.tets.bounds, 96.f / 80.f), 25.f, 15.f);
        const RenderResult a = renderCpu(sah, s), b = renderCpu(lbvh, s);
        double maxDiff = 0.0;
        for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
            const Vec4f d = a.image.pixels[i] - b.image.pixels[i];
            for (float c : {d.x, d.y, d.z, d.w}) maxDiff = std::max(maxDiff, double(std::fabs(c)));
        }
        EXPECT_LT(maxDiff, 2e-3) << (partitions ? "partitions" : "reference");
        EXPECT_NEAR(double(b.stats.samples), double(a.stats.samples), 1e-3 * a.stats.samples);
    }
}

}  // namespace
}  // namespace uvr

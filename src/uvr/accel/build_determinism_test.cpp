// SPDX-License-Identifier: MIT
// The parallel builders (BVH, face neighbours, k-d partitions, splitting, the kernels' layout) give
// bit-identical results whatever the thread count, on a mesh large enough for their data-parallel
// top levels.
#include <gtest/gtest.h>

#include "test_meshes.h"
#include "test_support.h"

#include <algorithm>
#include <cstring>
#include <map>

#include "uvr/accel/bvh.h"
#include "uvr/accel/kd_partitions.h"
#include "uvr/accel/tet_adjacency.h"
#include "uvr/cpu/threads.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/mesh/tet_math.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

/// Prepares bigBox with a thread count and k-d leaf size (cached: the tests share them).
const PreparedMesh& prepareWith(int threads, std::uint32_t leafCells) {
    static std::map<std::pair<int, std::uint32_t>, PreparedMesh> cache;
    const auto key = std::pair{threads, leafCells};
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    cpu::setThreadCount(threads);
    PrepareOptions options;
    options.kd.leafCells = leafCells;
    PreparedMesh pm =
        prepareMesh(testing::box400k(), selectScalarField(testing::box400k(), {}), options);
    cpu::setThreadCount(0);
    return cache.emplace(key, std::move(pm)).first->second;
}

TEST(ParallelBuild, SameResultsWithOneAndTwoThreads) {
    for (std::uint32_t leafCells : {1024u, 65536u}) {
        const PreparedMesh& a = prepareWith(1, leafCells);
        const PreparedMesh& b = prepareWith(2, leafCells);
        ASSERT_GT(a.tets.tets.size(), 300000u);
        EXPECT_TRUE(testing::sameBytes(a.tets.tets, b.tets.tets));
        EXPECT_EQ(a.tets.totalVolume, b.tets.totalVolume);
        EXPECT_TRUE(testing::sameBytes(a.bvh.nodes, b.bvh.nodes));
        EXPECT_TRUE(testing::sameBytes(a.bvh.primIds, b.bvh.primIds));
        EXPECT_TRUE(testing::sameBytes(a.neighbors, b.neighbors));
        EXPECT_TRUE(testing::sameBytes(a.kd->nodes, b.kd->nodes));
        EXPECT_TRUE(testing::sameBytes(a.kd->partitions, b.kd->partitions));
        EXPECT_TRUE(testing::sameBytes(a.kd->cells, b.kd->cells));
        // The kernels' layout: Morton order, blocks, neighbour codes, cell tree.
        EXPECT_TRUE(testing::sameBytes(a.tets.tetSourceOrder, b.tets.tetSourceOrder));
        EXPECT_TRUE(testing::sameBytes(a.tets.tetCorners, b.tets.tetCorners));
        EXPECT_TRUE(testing::sameBytes(a.tets.blockVertices, b.tets.blockVertices));
        EXPECT_TRUE(testing::sameBytes(a.neighborCodes.tetCodes, b.neighborCodes.tetCodes));
        EXPECT_TRUE(testing::sameBytes(a.neighborCodes.escapes, b.neighborCodes.escapes));
        EXPECT_TRUE(testing::sameBytes(a.cellTree.nodes, b.cellTree.nodes));
    }
}

TEST(ParallelBuild, SmoothGradientsAreTheSameBitsWithOneAndTwoThreads) {
    // Each point's sum over the cells around it, added to by several threads: float atomics gave
    // sums that differed in the last bits from run to run (and so shaded pixels, by 1/255).
    ProceduralSpec spec;
    spec.targetCells = 200000;
    spec.fields = {ProceduralField::Multiscale};
    const Mesh mesh = generateMesh(spec);
    const TetMesh prepared = prepareMesh(mesh, selectScalarField(mesh, {}), {}).tets;
    ASSERT_EQ(prepared.blockVertexPoint.size(), prepared.blockVertices.size());
    const auto gradients = [&](int threads) {
        TetMesh t = prepared;
        cpu::setThreadCount(threads);
        computeSmoothGradients(t);
        cpu::setThreadCount(0);
        return t.blockGradients;
    };
    const std::vector<Vec3f> one = gradients(1);
    ASSERT_EQ(one.size(), prepared.blockVertices.size());
    for (int run = 0; run < 3; ++run) EXPECT_TRUE(testing::sameBytes(one, gradients(2))) << run;
    // And right: each point's volume-weighted mean of its tetrahedra's gradients, summed here in
    // double one tetrahedron after the other, to float rounding.
    const TetMeshView v = prepared.view();
    std::vector<double> sums(4 * mesh.points.size(), 0.0);
    for (std::uint64_t t = 0; t < prepared.tetCount(); ++t) {
        BlockVertex x[4];
        v.tetVertices(t, x);
        const Vec3f g = tetGradient(x[0].p, x[1].p, x[2].p, x[3].p, x[0].value, x[1].value,
                                    x[2].value, x[3].value);
        const double w = std::fabs(signedVolume6(x[0].p, x[1].p, x[2].p, x[3].p)) / 6.0;
        const std::uint32_t base = prepared.blockVertexBase[t >> kTetBlockBits];
        for (const std::uint16_t k : prepared.tetCorners[t].v) {
            double* s = &sums[4 * prepared.blockVertexPoint[base + k]];
            s[0] += w * g.x, s[1] += w * g.y, s[2] += w * g.z, s[3] += w;
        }
    }
    float worst = 0.f;
    for (std::uint64_t i = 0; i < one.size(); ++i) {
        const double* s = &sums[4 * prepared.blockVertexPoint[i]];
        const Vec3f want(float(s[0] / s[3]), float(s[1] / s[3]), float(s[2] / s[3]));
        worst = std::max(worst, length(one[i] - want) / std::max(length(want), 1e-6f));
    }
    EXPECT_LT(worst, 1e-5f);
}

TEST(ParallelBuild, LargeBvhHoldsEveryPrimitiveOnceInNestedBoxes) {
    const PreparedMesh& pm = prepareWith(2, 65536);
    const Bvh& bvh = pm.bvh;
    std::vector<int> seen(pm.tets.tets.size(), 0);
    std::vector<Bounds3f> boxes;
    std::vector<Vec3f> centers;
    tetBoxesAndCenters(pm.tets, boxes, centers);
    int maxDepth = 0;
    std::vector<std::pair<std::uint32_t, int>> stack{{0, 1}};
    auto inside = [](const Bounds3f& inner, const Bounds3f& outer) {
        for (int a = 0; a < 3; ++a)
            if (inner.lo[a] < outer.lo[a] || inner.hi[a] > outer.hi[a]) return false;
        return true;
    };
    while (!stack.empty()) {
        const auto [node, depth] = stack.back();
        stack.pop_back();
        maxDepth = std::max(maxDepth, depth);
        const BvhNode& n = bvh.nodes[node];
        if (n.count > 0) {
            for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
                ++seen[bvh.primIds[i]];
                ASSERT_TRUE(inside(boxes[bvh.primIds[i]], n.box));
            }
            continue;
        }
        ASSERT_LT(n.first + 1, bvh.nodes.size());
        ASSERT_TRUE(inside(bvh.nodes[n.first].box, n.box));
        ASSERT_TRUE(inside(bvh.nodes[n.first + 1].box, n.box));
        stack.push_back({n.first, depth + 1});
        stack.push_back({n.first + 1, depth + 1});
    }
    EXPECT_LE(maxDepth, kBvhMaxDepth);
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
}

TEST(ParallelBuild, NeighboursMatchASortOfAllFaces) {
    const PreparedMesh& pm = prepareWith(2, 65536);
    // Reference: sort every face by its sorted vertex ids, pair equal neighbours.
    struct Face {
        std::uint32_t v[3];
        std::uint32_t slot;
    };
    std::vector<Face> faces;
    for (std::uint32_t t = 0; t < pm.tets.tets.size(); ++t)
        for (int i = 0; i < 4; ++i) {
            Face f{{}, 4 * t + i};
            int k = 0;
            for (int j = 0; j < 4; ++j)
                if (j != i) f.v[k++] = pm.tets.tets[t].v[j];
            std::sort(f.v, f.v + 3);
            faces.push_back(f);
        }
    std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
        return std::lexicographical_compare(a.v, a.v + 3, b.v, b.v + 3);
    });
    std::vector<std::uint32_t> expected(pm.neighbors.size(), kNoTet);
    auto same = [](const Face& a, const Face& b) { return std::equal(a.v, a.v + 3, b.v); };
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && same(faces[i], faces[j])) ++j;
        if (j - i == 2) {
            expected[faces[i].slot] = faces[i + 1].slot / 4;
            expected[faces[i + 1].slot] = faces[i].slot / 4;
        }
        i = j;
    }
    EXPECT_EQ(pm.neighbors, expected);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// GPU tests of the LBVH builder: skipped without a CUDA device (and refused clearly in a build
// without CUDA); run on the GPU machine.
#include "uvr/cuda/cuda_lbvh.h"

#include <gtest/gtest.h>

#include <cstring>

#include "test_meshes.h"
#include "uvr/core/error.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/render_setup.h"

namespace uvr {
namespace {

#define UVR_REQUIRE_GPU() \
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription()

bool sameNodes(const std::vector<BvhNode>& a, const std::vector<BvhNode>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(BvhNode)) == 0;
}

TetMesh proceduralTets(std::uint64_t cells) {
    ProceduralSpec spec;
    spec.targetCells = cells;
    const Mesh m = generateMesh(spec);
    return tetrahedralize(m, selectScalarField(m, {}));
}

TEST(CudaLbvh, WithoutADeviceTheBuildIsRefusedClearly) {
    if (cudaDeviceAvailable()) GTEST_SKIP() << "a CUDA device is present";
    const Mesh m = testing::makeHexGrid(2, 0.f, 1.f, [](Vec3f p) { return p.x; });
    const TetMesh mesh = tetrahedralize(m, selectScalarField(m, {}));
    EXPECT_THROW(buildMeshLbvh(mesh, buildLbvhCuda), Error);
}

TEST(CudaLbvh, MeshTreeIsBitIdenticalToTheCpuBuild) {
    UVR_REQUIRE_GPU();
    const TetMesh mesh = proceduralTets(300000);
    for (int leaf : {1, 4}) {
        const Bvh cpu = buildMeshLbvh(mesh, buildLbvhCpu, leaf);
        const Bvh gpu = buildMeshLbvh(mesh, buildLbvhCuda, leaf);
        EXPECT_TRUE(sameNodes(cpu.nodes, gpu.nodes)) << "leaf size " << leaf;
        EXPECT_EQ(cpu.primIds, gpu.primIds) << "leaf size " << leaf;
    }
}

TEST(CudaLbvh, PartitionTreesAreBitIdenticalToTheCpuBuild) {
    UVR_REQUIRE_GPU();
    const TetMesh mesh = proceduralTets(200000);
    KdBuildOptions o;
    o.leafCells = 4096;
    o.lbvh = buildLbvhCpu;
    const KdPartitions cpu = buildKdPartitions(mesh, o);
    o.lbvh = buildLbvhCuda;
    const KdPartitions gpu = buildKdPartitions(mesh, o);
    ASSERT_GT(cpu.partitions.size(), 16u);
    EXPECT_TRUE(sameNodes(cpu.bvhNodes, gpu.bvhNodes));
    EXPECT_EQ(cpu.cells, gpu.cells);
    ASSERT_EQ(cpu.partitions.size(), gpu.partitions.size());
    for (std::size_t p = 0; p < cpu.partitions.size(); ++p)
        ASSERT_EQ(cpu.partitions[p].bvhRoot, gpu.partitions[p].bvhRoot) << p;
}

}  // namespace
}  // namespace uvr

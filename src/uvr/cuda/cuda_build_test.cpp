// SPDX-License-Identifier: MIT
// GPU tests of the GPU builders (linear BVHs, k-d trees): skipped without a CUDA device (and
// refused clearly in a build without CUDA); run on the GPU machine.
#include "uvr/cuda/cuda_build.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <tuple>

#include "on_each_device.h"
#include "prepared_checks.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/facade/frame_report.h"
#include "uvr/facade/renderer.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

bool sameNodes(const std::vector<BvhNode>& a, const std::vector<BvhNode>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(BvhNode)) == 0;
}

/// The built-in procedural mesh of about `cells` cells.
Mesh proceduralMesh(std::uint64_t cells) {
    ProceduralSpec spec;
    spec.targetCells = cells;
    return generateMesh(spec);
}

TetMesh proceduralTets(std::uint64_t cells) {
    const Mesh m = proceduralMesh(cells);
    return tetrahedralize(m, selectScalarField(m, {}), {.splitCells = true});
}

TEST(CudaLbvh, WithoutADeviceTheBuildIsRefusedClearly) {
    if (cudaDeviceAvailable()) GTEST_SKIP() << "a CUDA device is present";
    const Mesh m = testing::makeHexGrid(2, 0.f, 1.f, [](Vec3f p) { return p.x; });
    const TetMesh mesh = tetrahedralize(m, selectScalarField(m, {}), {.splitCells = true});
    EXPECT_THROW(buildMeshLbvh(mesh, buildLbvhCuda), Error);
    EXPECT_THROW(buildKdTreeCuda(mesh, {}), Error);
    EXPECT_THROW(buildTetNeighborsCuda(mesh), Error);
    EXPECT_THROW(tetrahedralize(m, selectScalarField(m, {}), {.sorter = sortCellKeysCuda}), Error);
    EXPECT_THROW(buildSeedGridsCuda(mesh, buildKdPartitions(mesh, {}), kTetsPerSeedCell), Error);
    EXPECT_THROW(buildMacroGridsCuda(mesh, buildKdPartitions(mesh, {}), buildTetNeighbors(mesh),
                                     kTetsPerMacroCell),
                 Error);
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

TEST(CudaLbvh, SegmentedTreesAreBitIdenticalToTheCpuBuild) {
    UVR_REQUIRE_GPU();
    // One tree per k-d partition's cells: many segments of the one build.
    const TetMesh mesh = proceduralTets(200000);
    KdBuildOptions o;
    o.leafCells = 4096;
    const KdPartitions kd = buildKdPartitions(mesh, o);
    ASSERT_GT(kd.partitions.size(), 16u);
    LbvhInput in;
    in.mesh = &mesh;
    in.tetIds = kd.cells;
    for (const KdPartition& p : kd.partitions) {
        in.segmentBegin.push_back(p.firstCell);
        in.segmentBounds.push_back(p.box);
    }
    in.segmentBegin.push_back(kd.cells.size());
    in.leafSize = 8;
    const LbvhResult cpu = buildLbvhCpu(in);
    const LbvhResult gpu = buildLbvhCuda(in);
    EXPECT_TRUE(sameNodes(cpu.nodes, gpu.nodes));
    EXPECT_EQ(cpu.order, gpu.order);
    EXPECT_EQ(cpu.roots, gpu.roots);
}

/// The partitions as a comparable set: (shrunk box, value range, cells in order) by box.
std::vector<std::tuple<std::vector<float>, float, float, std::vector<std::uint32_t>>> partitionSet(
    const KdPartitions& kd) {
    std::vector<std::tuple<std::vector<float>, float, float, std::vector<std::uint32_t>>> out;
    for (const KdPartition& p : kd.partitions) {
        std::vector<std::uint32_t> cells(kd.cells.begin() + p.firstCell,
                                         kd.cells.begin() + p.firstCell + p.cellCount);
        out.push_back({{p.box.lo.x, p.box.lo.y, p.box.lo.z, p.box.hi.x, p.box.hi.y, p.box.hi.z},
                       p.valueMin,
                       p.valueMax,
                       std::move(cells)});
    }
    std::sort(out.begin(), out.end());
    return out;
}

TEST(CudaKd, SameSplitsLeavesAndCellsAsTheCpuBuild) {
    UVR_REQUIRE_GPU();
    for (const std::uint64_t cells : {1000ull, 300000ull}) {
        const TetMesh mesh = proceduralTets(cells);
        for (const std::uint32_t leafCells : {64u, 4096u}) {
            KdBuildOptions o;
            o.leafCells = leafCells;
            const KdPartitions cpu = buildKdPartitions(mesh, o);
            o.splitter = buildKdTreeCuda;
            const KdPartitions gpu = buildKdPartitions(mesh, o);
            ASSERT_EQ(cpu.nodes.size(), gpu.nodes.size()) << cells << " / " << leafCells;
            ASSERT_EQ(cpu.partitions.size(), gpu.partitions.size());
            EXPECT_TRUE(partitionSet(cpu) == partitionSet(gpu)) << cells << " / " << leafCells;
            // The trees locate points in partitions of the same box.
            std::mt19937 rng(9);
            std::uniform_real_distribution<float> u(0.f, 1.f);
            for (int q = 0; q < 2000; ++q) {
                const Vec3f p = mesh.bounds.lo +
                                (mesh.bounds.hi - mesh.bounds.lo) * Vec3f(u(rng), u(rng), u(rng));
                auto leafBox = [&](const KdPartitions& kd) {
                    std::uint32_t node = 0;
                    while (!kd.nodes[node].isLeaf()) {
                        const KdNode n = kd.nodes[node];
                        node = n.child() + (p[n.axis()] <= n.split ? 0u : 1u);
                    }
                    return kd.partitions[kd.nodes[node].child()].box;
                };
                const Bounds3f a = leafBox(cpu), b = leafBox(gpu);
                ASSERT_TRUE(a.lo == b.lo && a.hi == b.hi) << "query " << q;
            }
        }
    }
}

TEST(CudaKd, ASubtreeBelowALargerTreesNodeIsTheCpuBuilds) {
    UVR_REQUIRE_GPU();
    const TetMesh mesh = proceduralTets(300000);
    KdBuildOptions whole;
    whole.leafCells = 4096;
    const KdPartitions tree = buildKdPartitions(mesh, whole);
    // The node two levels down on the upper sides (a data-parallel rank's), and a node beside
    // the mesh that no cell reaches.
    Bounds3f region = mesh.bounds;
    std::uint32_t node = 0;
    for (int depth = 0; depth < 2; ++depth) {
        const KdNode n = tree.nodes[node];
        ASSERT_FALSE(n.isLeaf());
        region.lo[n.axis()] = n.split;
        node = n.child() + 1;
    }
    Bounds3f beside = mesh.bounds;
    const float width = beside.hi.x - beside.lo.x;
    beside.lo.x = beside.hi.x + width, beside.hi.x += 2.f * width;
    for (const auto& [root, depth] : {std::pair{region, 2}, std::pair{beside, 1}}) {
        KdBuildOptions o = whole;
        o.root = KdSubtreeRoot{root, depth, mesh.bounds.diagonal()};
        const KdPartitions cpu = buildKdPartitions(mesh, o);
        o.splitter = buildKdTreeCuda;
        const KdPartitions gpu = buildKdPartitions(mesh, o);
        if (depth == 2)
            EXPECT_GT(cpu.partitions.size(), 4u);
        else
            EXPECT_EQ(cpu.partitions.size(), 1u);
        ASSERT_EQ(cpu.nodes.size(), gpu.nodes.size()) << "depth " << depth;
        ASSERT_EQ(cpu.partitions.size(), gpu.partitions.size());
        EXPECT_TRUE(partitionSet(cpu) == partitionSet(gpu)) << "depth " << depth;
    }
}

TEST(CudaKd, TheBuildHoldsTheBoxesAndAboutTwentyBytesPerListedCell) {
    UVR_REQUIRE_GPU();
    // The bound of kd_build.cu: the boxes (24 bytes a cell) and the level's list (4 bytes a
    // listed cell) throughout, and at most 16 more a listed cell (the sort's keys, or the side
    // scans and the next list); or, while the boxes are made, the cells as uploaded. A billion
    // tetrahedra must build well inside an 80 GB card. The build of before held 48 bytes a
    // listed cell besides the boxes.
    const TetMesh mesh = proceduralTets(2000000);
    const std::uint64_t n = mesh.cellCount();
    KdBuildOptions o;
    o.leafCells = 4096;
    o.splitter = buildKdTreeCuda;
    resetCudaMemoryPeak();
    const std::uint64_t before = cudaMemoryUse().bytes;
    const KdPartitions kd = buildKdPartitions(mesh, o);
    const std::uint64_t peak = cudaMemoryUse().peakBytes - before;
    EXPECT_EQ(cudaMemoryUse().bytes, before);      // all of it given back
    const std::uint64_t listed = kd.cells.size();  // the last level's, the most of any
    ASSERT_GE(listed, n);
    const std::uint64_t uploads = 24 * n + 4 * n + mesh.tets.size() * sizeof(Tet) +
                                  mesh.points.size() * sizeof(Vec3f) +
                                  mesh.nativeCorners.size() * sizeof(std::uint32_t);
    const std::uint64_t bound = std::max(uploads, 24 * n + 20 * listed);
    EXPECT_LE(peak, bound + bound / 50 + (std::uint64_t(32) << 20))
        << peak / double(n) << " bytes a cell at the peak, " << listed / double(n)
        << " listed cells a cell";
    EXPECT_GT(peak, 24 * n);  // the count sees the build at all
}

/// Meshes for the face and seed builders: tetrahedra only, mixed native cells, and tetrahedra
/// with a seam of duplicated points across every other cell (welded faces) and a face shared by
/// three tetrahedra (left a boundary).
std::vector<std::pair<std::string, TetMesh>> builderMeshes() {
    std::vector<std::pair<std::string, TetMesh>> out;
    out.emplace_back("tetrahedra", proceduralTets(300000));
    const Mesh mixed = generateMixedCellMesh(24);
    out.emplace_back("mixed cells", tetrahedralize(mixed, selectScalarField(mixed, {}), {}));
    Mesh seams = testing::seamMesh(20000);
    for (std::size_t i = 0; i < seams.fields[0].values.size(); i += 101)
        seams.fields[0].values[i] = NAN;  // NaN point values
    out.emplace_back("seams",
                     tetrahedralize(seams, selectScalarField(seams, {}), {.splitCells = true}));
    Field cellField{"c", Association::Cell, 1, {}};
    for (std::size_t c = 0; c < seams.cellCount(); ++c)
        cellField.values.push_back(c % 97 == 0 ? NAN : float(c % 13));
    seams.fields.push_back(cellField);
    FieldSpec cellSpec;
    cellSpec.name = "c";
    out.emplace_back("cell data", tetrahedralize(seams, selectScalarField(seams, cellSpec),
                                                 {.splitCells = true}));
    return out;
}

TEST(CudaPrepare, FaceNeighboursEqualTheCpuTable) {
    UVR_REQUIRE_GPU();
    for (const auto& [name, mesh] : builderMeshes()) {
        const std::vector<std::uint32_t> cpu = buildTetNeighbors(mesh);
        EXPECT_EQ(buildTetNeighborsCuda(mesh), cpu) << name;
        // In passes over vertex ranges, as when the faces do not fit at once.
        EXPECT_EQ(buildTetNeighborsCuda(mesh, {}, mesh.view().faceSlots() / 7 + 64), cpu) << name;
    }
}

TEST(CudaPrepare, SeedGridsEqualTheCpuSeeds) {
    UVR_REQUIRE_GPU();
    for (const auto& [name, mesh] : builderMeshes()) {
        KdBuildOptions o;
        o.leafCells = 2048;
        const KdPartitions kd = buildKdPartitions(mesh, o);
        const SeedGrids cpu = buildSeedGrids(mesh, kd);
        const SeedGrids gpu = buildSeedGridsCuda(mesh, kd, kTetsPerSeedCell);
        ASSERT_EQ(cpu.grids.size(), gpu.grids.size()) << name;
        EXPECT_EQ(std::memcmp(cpu.grids.data(), gpu.grids.data(),
                              cpu.grids.size() * sizeof(PartitionGrid)),
                  0)
            << name;
        EXPECT_EQ(cpu.seeds, gpu.seeds) << name;
        EXPECT_GT(std::count_if(gpu.seeds.begin(), gpu.seeds.end(),
                                [](std::uint32_t t) { return t != kNoTet; }),
                  std::ptrdiff_t(gpu.seeds.size() / 2))
            << name;
    }
}

TEST(CudaPrepare, MacrocellsAndGradientSpreadsEqualTheCpus) {
    UVR_REQUIRE_GPU();
    for (const auto& [name, mesh] : builderMeshes()) {
        KdBuildOptions o;
        o.leafCells = 2048;
        const KdPartitions kd = buildKdPartitions(mesh, o);
        const std::vector<std::uint32_t> neighbors = buildTetNeighbors(mesh);
        const MacroGrids cpu = buildMacroGrids(mesh, kd, neighbors);
        const std::vector<float> cpuSpread = partitionGradientSpread(mesh, kd);
        const MacroBuild gpu = buildMacroGridsCuda(mesh, kd, neighbors, kTetsPerMacroCell);
        ASSERT_EQ(cpu.cells.size(), gpu.macro.cells.size()) << name;
        std::size_t differ = 0, edge = 0, visible = 0;
        for (std::size_t c = 0; c < cpu.cells.size(); ++c) {
            const MacroCell &a = cpu.cells[c], &b = gpu.macro.cells[c];
            // == : a zero may come back with the other sign.
            differ += !(a.valueMin == b.valueMin && a.valueMax == b.valueMax &&
                        a.gradientSpread == b.gradientSpread && a.atBoundary == b.atBoundary);
            edge += a.atBoundary;
            visible += !a.empty();
        }
        EXPECT_EQ(differ, 0u) << name;
        EXPECT_GT(edge, 0u) << name;  // the boundary's macrocells
        EXPECT_GT(visible, cpu.cells.size() / 2) << name;
        EXPECT_EQ(cpu.nanCells, gpu.macro.nanCells) << name;
        ASSERT_EQ(cpuSpread.size(), gpu.gradientSpread.size()) << name;
        for (std::size_t p = 0; p < cpuSpread.size(); ++p)
            ASSERT_EQ(cpuSpread[p], gpu.gradientSpread[p]) << name << ", partition " << p;
    }
}

TEST(CudaPrepare, MortonOrderEqualsTheCpus) {
    UVR_REQUIRE_GPU();
    for (const bool mixed : {false, true}) {
        const Mesh m = mixed ? generateMixedCellMesh(24) : proceduralMesh(300000);
        const ScalarField f = selectScalarField(m, {});
        const TetMesh cpu = tetrahedralize(m, f, {});
        const TetMesh gpu = tetrahedralize(m, f, {.sorter = sortCellKeysCuda});
        EXPECT_TRUE(testing::sameBytes(cpu.tets, gpu.tets)) << mixed;
        EXPECT_TRUE(testing::sameBytes(cpu.tetSourceOrder, gpu.tetSourceOrder)) << mixed;
        EXPECT_TRUE(testing::sameBytes(cpu.tetCorners, gpu.tetCorners)) << mixed;
        EXPECT_EQ(cpu.nativeCorners, gpu.nativeCorners) << mixed;
        EXPECT_EQ(cpu.nativeSource, gpu.nativeSource) << mixed;
    }
}

TEST(CudaKd, PreparedOnTheGpuRendersAsOnTheCpu) {
    UVR_REQUIRE_GPU();
    const Mesh m = proceduralMesh(200000);
    PrepareOptions o;
    o.kd.leafCells = 4096;
    const PreparedMesh cpu = prepareMesh(m, selectScalarField(m, {}), o);
    o.lbvh = buildLbvhCuda;
    o.kdSplitter = buildKdTreeCuda;
    const PreparedMesh gpu = prepareMesh(m, selectScalarField(m, {}), o);
    EXPECT_TRUE(gpu.builtElsewhere);
    RenderSettings s;
    s.width = 128;
    s.height = 96;
    s.method = RenderMethod::Partitions;
    s.tf = transferFunctionPreset("cool-to-warm");
    applyOpacitySpec(s.tf, "0:0,1:0.3");
    const RenderResult a = renderCpu(cpu, s), b = renderCpu(gpu, s);
    EXPECT_GE(compareImages(toRgb8(a.image), toRgb8(b.image)).ssim, 0.999);
    EXPECT_NEAR(double(b.stats.samples), double(a.stats.samples), 1e-3 * a.stats.samples);
}

/// Holds uvr's device memory to `bytes` while it lives.
struct CudaMemoryLimit {
    explicit CudaMemoryLimit(std::uint64_t bytes) { setCudaMemoryLimit(bytes); }
    ~CudaMemoryLimit() { setCudaMemoryLimit(0); }
    CudaMemoryLimit(const CudaMemoryLimit&) = delete;
    CudaMemoryLimit& operator=(const CudaMemoryLimit&) = delete;
};

TEST(CudaPrepare, WhenTheGpuLacksMemoryTheCpuBuildsTheSameMesh) {
    UVR_REQUIRE_GPU();
    const Mesh m = proceduralMesh(200000);
    const ScalarField f = selectScalarField(m, {});
    RendererOptions options;
    options.device = Device::Cpu;  // frames on the CPU: only the builders want the GPU
    options.buildDevice = Device::Cuda;
    options.leafCells = 4096;
    PreparedMesh fell;
    std::vector<std::string> heard;
    {
        const CudaMemoryLimit limit(std::uint64_t(1) << 20);  // a card of 1 MiB
        fell = prepareMesh(m, f, options.prepareOptions(),
                           ProgressFn([&](const std::string& line) { heard.push_back(line); }));
    }
    options.buildDevice = Device::Cpu;
    const PreparedMesh cpu = prepareMesh(m, f, options.prepareOptions());
    EXPECT_EQ(fell.builtOnCpuInstead,
              (std::vector<std::string>{"split", "bvh", "neighbours", "partitions", "seed_grids",
                                        "macrocells"}));
    EXPECT_FALSE(fell.builtElsewhere);
    EXPECT_TRUE(cpu.builtOnCpuInstead.empty());
    const auto says = [&](const std::string& what) {
        return std::any_of(heard.begin(), heard.end(), [&](const std::string& line) {
            return line.find("out of GPU memory allocating") != std::string::npos &&
                   line.find(what) != std::string::npos;
        });
    };
    EXPECT_TRUE(says("building the partitions on the CPU instead of the GPU"));
    EXPECT_TRUE(says("building the neighbours on the CPU instead of the GPU"));
    // The same mesh as the CPU's build, so the same frames.
    testing::expectSamePreparation(cpu, fell);
    EXPECT_TRUE(sameNodes(cpu.bvh.nodes, fell.bvh.nodes));
    // Without the limit the GPU builds again, and gives back all it took.
    const std::uint64_t held = cudaMemoryUse().bytes;
    options.buildDevice = Device::Cuda;
    const PreparedMesh again = prepareMesh(m, f, options.prepareOptions());
    EXPECT_TRUE(again.builtOnCpuInstead.empty());
    EXPECT_TRUE(again.builtElsewhere);
    EXPECT_EQ(cudaMemoryUse().bytes, held);
}

TEST(CudaPrepare, WhenTheGpuCannotHoldTheMeshAutoRendersOnTheCpu) {
    UVR_REQUIRE_GPU();
    const Mesh m = proceduralMesh(100000);
    const ScalarField f = selectScalarField(m, {});
    RenderSettings s;
    s.width = 80;
    s.height = 60;
    s.tf = transferFunctionPreset("cool-to-warm");
    RendererOptions cpuOnly;
    cpuOnly.device = Device::Cpu;
    Renderer onCpu(m, f, cpuOnly);
    const RenderResult want = onCpu.render(s);
    std::vector<std::string> heard;
    {
        const CudaMemoryLimit limit(std::uint64_t(1) << 20);  // a card of 1 MiB
        Renderer r(m, f, RendererOptions{},
                   ProgressFn([&](const std::string& line) { heard.push_back(line); }));
        EXPECT_FALSE(r.onGpu());
        EXPECT_STREQ(r.deviceName(), "cpu");
        EXPECT_NE(r.deviceFallback().find("out of GPU memory allocating"), std::string::npos);
        EXPECT_NE(r.deviceFallback().find("rendering on the CPU instead"), std::string::npos);
        EXPECT_NE(std::find(heard.begin(), heard.end(), r.deviceFallback()), heard.end());
        EXPECT_EQ(frameReport(r, s, r.render(s)).value("device_fallback", ""), r.deviceFallback());
        // The CPU's choice of method, and its picture.
        EXPECT_FALSE(r.prepared().autoChoice->gpu);
        const RenderResult got = r.render(s);
        EXPECT_GE(compareImages(toRgb8(want.image), toRgb8(got.image)).ssim, 0.99);
        // Asking for the GPU keeps the error.
        EXPECT_THROW(
            {
                try {
                    RendererOptions cuda;
                    cuda.device = Device::Cuda;
                    Renderer(m, f, cuda);
                } catch (const Error& e) {
                    EXPECT_EQ(e.kind(), ErrorKind::Resource);
                    throw;
                }
            },
            Error);
    }
    // With the memory back, frames render on the GPU again.
    const Renderer onGpu(m, f);
    EXPECT_TRUE(onGpu.onGpu());
    EXPECT_TRUE(onGpu.deviceFallback().empty());
}

}  // namespace
}  // namespace uvr

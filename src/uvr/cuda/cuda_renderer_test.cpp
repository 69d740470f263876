// SPDX-License-Identifier: MIT
// GPU tests: skipped without a CUDA device; run on the GPU machine before GPU work is resolved.
#include "uvr/cuda/cuda_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "on_each_device.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

RenderSettings settingsFor(const PreparedMesh& pm, RenderMethod method) {
    RenderSettings s;
    s.width = 160;
    s.height = 120;
    s.method = method;
    s.tf = transferFunctionPreset("cool-to-warm");
    applyOpacitySpec(s.tf, "0:0,1:0.4");
    s.camera = orbitCamera(resetCamera(pm.tets.bounds, 160.f / 120.f), 30.f, 20.f);
    return s;
}

/// CPU and GPU run the same code on the same data: images agree to rounding, counts nearly (a
/// sample on a shared face may resolve to either tetrahedron, a ray grazing a partition's box may
/// enter it on one processor and miss it on the other: the GPU fuses multiply-adds).
void expectSameAsCpu(const PreparedMesh& pm, const RenderSettings& s, const std::string& what) {
    CudaScene gpu(pm);
    const RenderResult c = renderCpu(pm, s);
    const RenderResult g = gpu.render(s);
    const double ssim = compareImages(toRgb8(c.image), toRgb8(g.image)).ssim;
    EXPECT_GE(ssim, 0.99) << what;
    EXPECT_NEAR(double(g.stats.samples), double(c.stats.samples), 0.001 * c.stats.samples) << what;
    EXPECT_NEAR(double(g.stats.partitionsVisited), double(c.stats.partitionsVisited),
                0.001 * c.stats.partitionsVisited)
        << what;
    EXPECT_GT(gpu.geometryBytes(), 0u);
    EXPECT_EQ(gpu.geometryBytes(), cudaSceneBytes(pm)) << what;  // the upload's progress line
}

TEST(Cuda, DescriptionIsOneLine) {
    const std::string d = cudaDeviceDescription();
    EXPECT_FALSE(d.empty());
    EXPECT_EQ(d.find('\n'), std::string::npos);
}

TEST(Cuda, WithoutADeviceTheSceneIsRefusedClearly) {
    if (cudaDeviceAvailable()) GTEST_SKIP() << "a CUDA device is present";
    Mesh m = testing::makeHexGrid(2, 0.f, 1.f);
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}));
    try {
        CudaScene scene(pm);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    }
}

TEST(Cuda, ProceduralMeshMatchesCpuForEveryMethod) {
    UVR_REQUIRE_GPU();
    Mesh m = testing::makeHexGrid(
        12, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f);
    PrepareOptions o;
    o.kd.leafCells = 128;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
    expectSameAsCpu(pm, settingsFor(pm, RenderMethod::Reference), "reference");
    expectSameAsCpu(pm, settingsFor(pm, RenderMethod::Exact), "exact");
    RenderSettings s = settingsFor(pm, RenderMethod::Partitions);
    expectSameAsCpu(pm, s, "skipping + adaptive");
    s.skip = false;
    expectSameAsCpu(pm, s, "adaptive only");
    s.skip = true;
    s.adaptive = false;
    expectSameAsCpu(pm, s, "skipping only");
}

TEST(Cuda, ParallelProjectionAndSupersamplingMatchCpuForEveryMethod) {
    // The shared pixel kernel's N x N rays (stratified and jittered) and the parallel camera's
    // per-pixel origins, on both devices.
    UVR_REQUIRE_GPU();
    Mesh m = testing::makeHexGrid(
        12, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f);
    PrepareOptions o;
    o.kd.leafCells = 128;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
    for (RenderMethod method :
         {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact}) {
        RenderSettings s = settingsFor(pm, method);
        s.camera->parallelProjection = true;
        s.camera->parallelScale = 1.2f;
        s.supersample = 3;
        expectSameAsCpu(pm, s, "parallel, supersample 3");
        s.jitter = true;
        s.camera->parallelProjection = false;
        expectSameAsCpu(pm, s, "perspective, supersample 3, jittered");
        CudaScene gpu(pm);
        const RenderResult g = gpu.render(s);
        EXPECT_EQ(g.stats.supersample, 3);
        std::uint64_t sum = 0;
        for (std::uint32_t c : g.sampleCounts) sum += c;
        EXPECT_EQ(sum, g.stats.samples);
    }
}

TEST(Cuda, NanColourAndLogScaleMatchCpuForEveryMethod) {
    // The NaN flags of partitions and macrocells (shaded by their own kernel on the GPU), the
    // NaN entry of the table, and a log-scale table of many entries, on both devices.
    UVR_REQUIRE_GPU();
    Mesh m = testing::makeHexGrid(12, 0.f, 1.f, [](Vec3f p) {
        return p.x > 0.51f ? std::numeric_limits<float>::quiet_NaN() : 0.001f + p.x * p.y;
    });
    PrepareOptions o;
    o.kd.leafCells = 64;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
    ASSERT_FALSE(pm.partitionNan.empty());
    for (RenderMethod method :
         {RenderMethod::Reference, RenderMethod::Partitions, RenderMethod::Exact}) {
        RenderSettings s = settingsFor(pm, method);
        s.tf.nanColor = Vec3f(1.f, 0.f, 0.f);
        s.tf.nanOpacity = 0.6f;
        expectSameAsCpu(pm, s, "NaN colour");
        s.tf.logScale = true;
        expectSameAsCpu(pm, s, "NaN colour, log scale");
    }
}

TEST(Cuda, RealMeshesMatchCpu) {
    UVR_REQUIRE_GPU();
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    for (const char* name : {"bluntfin_tets.vtk", "fire_ug.vtu", "spx.vtk"}) {
        const Mesh mesh = readMesh(testing::sharedData(name));
        const PreparedMesh pm = prepareMesh(mesh, selectScalarField(mesh, {}));
        expectSameAsCpu(pm, settingsFor(pm, RenderMethod::Reference), std::string(name) + " ref");
        expectSameAsCpu(pm, settingsFor(pm, RenderMethod::Partitions),
                        std::string(name) + " adaptive");
        expectSameAsCpu(pm, settingsFor(pm, RenderMethod::Exact), std::string(name) + " exact");
    }
}

TEST(Cuda, PartitionShadingOnTheGpuEqualsTheCpus) {
    UVR_REQUIRE_GPU();
    Mesh m = testing::makeHexGrid(
        12, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f);
    PrepareOptions o;
    o.kd.leafCells = 64;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
    CudaScene gpu(pm);
    for (const char* opacity :
         {"0:0,1:0.4", "step:0.6", "constant:0.2", "0:0,0.49:0,0.5:1,0.51:0,1:0"}) {
        RenderSettings s = settingsFor(pm, RenderMethod::Partitions);
        applyOpacitySpec(s.tf, opacity);
        const FrameSetup cpu = makeFrameSetup(pm, s);
        const RenderResult g = gpu.render(s);
        ASSERT_EQ(g.setup.shading.size(), cpu.shading.size());
        for (size_t p = 0; p < cpu.shading.size(); ++p) {
            // Same code; only fused multiply-adds may round differently on the GPU.
            EXPECT_NEAR(g.setup.shading[p].maxOpacity, cpu.shading[p].maxOpacity, 1e-6f) << opacity;
            EXPECT_EQ(g.setup.shading[p].maxOpacity > 0.f, cpu.shading[p].maxOpacity > 0.f);
            EXPECT_NEAR(g.setup.shading[p].step, cpu.shading[p].step, 1e-5f * cpu.shading[p].step)
                << opacity;
            // The macrocells' shading stays on the GPU; its per-partition choice comes back.
            EXPECT_EQ(g.setup.shading[p].byMacroCells, cpu.shading[p].byMacroCells) << opacity;
        }
    }
}

TEST(Cuda, TransferFunctionChangesReuseTheUploadedGeometry) {
    UVR_REQUIRE_GPU();
    Mesh m = testing::makeHexGrid(8, -1.f, 1.f, [](Vec3f p) { return p.x; });
    PrepareOptions o;
    o.kd.leafCells = 64;
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
    CudaScene gpu(pm);
    const std::uint64_t bytes = gpu.geometryBytes();
    RenderSettings s = settingsFor(pm, RenderMethod::Partitions);
    const RenderResult a = gpu.render(s);
    applyOpacitySpec(s.tf, "step:0.75");  // partitions with x < 0.5 become transparent
    const RenderResult b = gpu.render(s);
    EXPECT_EQ(gpu.geometryBytes(), bytes);
    EXPECT_GT(b.stats.partitionsSkipped, a.stats.partitionsSkipped);
    EXPECT_LT(compareImages(toRgb8(a.image), toRgb8(b.image)).ssim, 0.999);
}

TEST(Cuda, MeshesAndFieldsAtTheEdgesOfFloatMatchCpu) {
    // The GPU renders the prepared mesh's scaled and shifted frame (MeshFrame) and the transfer
    // function over a range wider than float, as the CPU does: coordinates near 1e38, a mesh
    // 1e-30 across, one far from the origin for its size, and a field spanning +-3e38.
    UVR_REQUIRE_GPU();
    struct Case {
        const char* name;
        float scale, offset, field;
    };
    const Case cases[] = {{"2^126", std::ldexp(1.f, 126), 0.f, 1.f},
                          {"2^-100", std::ldexp(1.f, -100), 0.f, 1.f},
                          {"far", 1.f, std::ldexp(1.f, 12), 1.f},
                          {"field 3e38", 1.f, 0.f, 3e38f}};
    for (const Case& c : cases) {
        Mesh m = testing::makeHexGrid(
            6, -0.5f, 0.5f, [&](Vec3f p) { return (p.x + 2.f * p.y - p.z) / 2.f * c.field; }, 0.2f);
        for (Vec3f& p : m.points) p = p * c.scale + Vec3f(c.offset, 0.f, -c.offset);
        PrepareOptions o;
        o.kd.leafCells = 32;
        const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), o);
        EXPECT_EQ(pm.tets.frame.identity(), c.field != 1.f) << c.name;
        RenderSettings s = settingsFor(pm, RenderMethod::Reference);
        s.camera.reset();  // the default camera, fitted in the file's coordinates
        expectSameAsCpu(pm, s, std::string(c.name) + " reference");
        s.method = RenderMethod::Partitions;
        expectSameAsCpu(pm, s, std::string(c.name) + " adaptive");
    }
}

}  // namespace
}  // namespace uvr

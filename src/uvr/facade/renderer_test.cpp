// SPDX-License-Identifier: MIT
#include "uvr/facade/renderer.h"

#include <gmock/gmock.h>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;

Mesh jitteredGrid() {
    return testing::makeHexGrid(
        10, -1.f, 1.f, [](Vec3f p) { return p.x * p.y + p.z; }, 0.3f);
}

RenderSettings frameOf(const Bounds3f& bounds, RenderMethod method) {
    RenderSettings s;
    s.width = 96;
    s.height = 64;
    s.method = method;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,1:0.5");
    s.camera = orbitCamera(resetCamera(bounds, 96.f / 64.f), 25.f, 15.f);
    return s;
}

TEST(Renderer, RendersEveryMethodAsTheBackendDoesOnThePreparedMesh) {
    const Mesh m = jitteredGrid();
    const ScalarField f = selectScalarField(m, {});
    RendererOptions o;
    o.device = Device::Cpu;
    o.leafCells = 64;
    Renderer r(m, f, o);
    EXPECT_STREQ(r.deviceName(), "cpu");
    EXPECT_FALSE(r.onGpu());
    EXPECT_GT(r.prepareSeconds(), 0.0);
    ASSERT_TRUE(r.prepared().kd);
    EXPECT_FALSE(r.prepared().bvh.nodes.empty());
    EXPECT_THAT(r.deviceDescription(), HasSubstr("threads"));
    // The same frames as the backend renders from an independent preparation, bit for bit.
    PrepareOptions po;
    po.kd.leafCells = 64;
    const PreparedMesh pm = prepareMesh(m, f, po);
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        const RenderSettings s = frameOf(m.bounds(), method);
        const RenderResult a = r.render(s), b = renderCpu(pm, s);
        ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size());
        EXPECT_EQ(a.stats.samples, b.stats.samples) << int(method);
        for (std::size_t i = 0; i < a.image.pixels.size(); ++i) {
            const Vec4f p = a.image.pixels[i], q = b.image.pixels[i];
            ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z && p.w == q.w) << "pixel " << i;
        }
        EXPECT_GT(a.stats.samples, 0u);
    }
}

TEST(Renderer, AMethodWhoseStructuresWereNotPreparedIsRefused) {
    const Mesh m = jitteredGrid();
    RendererOptions o;
    o.device = Device::Cpu;
    o.meshBvh = false;
    Renderer adaptiveOnly(m, selectScalarField(m, {}), o);
    EXPECT_THAT(catchError([&] {
                    adaptiveOnly.render(frameOf(m.bounds(), RenderMethod::Reference));
                }).what(),
                HasSubstr("mesh BVH"));
    o.meshBvh = true;
    o.partitions = false;
    Renderer referenceOnly(m, selectScalarField(m, {}), o);
    EXPECT_THAT(catchError([&] {
                    referenceOnly.render(frameOf(m.bounds(), RenderMethod::Partitions));
                }).what(),
                HasSubstr("k-d partitions"));
}

TEST(Renderer, DevicesParseAndCudaWithoutADeviceIsRefused) {
    EXPECT_EQ(parseDevice("auto", "device"), Device::Auto);
    EXPECT_EQ(parseDevice("cpu", "device"), Device::Cpu);
    EXPECT_EQ(parseDevice("cuda", "device"), Device::Cuda);
    const Error e = catchError([] { parseDevice("gpu", "--device"); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("--device: expected auto, cpu or cuda, got \"gpu\""));
    EXPECT_FALSE(resolvesToCuda(Device::Cpu));
    EXPECT_EQ(resolvesToCuda(Device::Auto), cudaDeviceAvailable());
    if (cudaDeviceAvailable()) return;
    const Mesh m = jitteredGrid();
    RendererOptions o;
    o.device = Device::Cuda;
    EXPECT_EQ(catchError([&] { Renderer r(m, selectScalarField(m, {}), o); }).kind(),
              ErrorKind::Unsupported);
}

TEST(Renderer, OnTheGpuFramesMatchTheCpu) {
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    const Mesh m = jitteredGrid();
    const ScalarField f = selectScalarField(m, {});
    RendererOptions o;
    o.leafCells = 64;
    o.device = Device::Cpu;
    Renderer cpu(m, f, o);
    o.device = Device::Cuda;
    Renderer gpu(m, f, o);
    EXPECT_TRUE(gpu.onGpu());
    EXPECT_STREQ(gpu.deviceName(), "cuda");
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        const RenderSettings s = frameOf(m.bounds(), method);
        const double ssim =
            compareImages(toRgb8(cpu.render(s).image), toRgb8(gpu.render(s).image)).ssim;
        EXPECT_GE(ssim, 0.99) << int(method);
    }
}

}  // namespace
}  // namespace uvr

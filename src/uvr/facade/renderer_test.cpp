// SPDX-License-Identifier: MIT
#include "uvr/facade/renderer.h"

#include <gmock/gmock.h>

#include <cmath>
#include <cstring>

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
    const Mesh m = testing::jitteredHexGrid(10);
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

TEST(Renderer, TheSourceMeshFreedOnceSplitChangesNoFrame) {
    const Mesh kept = testing::jitteredHexGrid(10);
    Mesh freed = kept;
    const ScalarField f = selectScalarField(kept, {});
    RendererOptions o;
    o.device = Device::Cpu;
    o.leafCells = 64;
    Renderer a(kept, f, o);
    int calls = 0;
    o.afterSplit = [&] { freed = Mesh(), ++calls; };
    Renderer b(freed, f, o);
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(freed.cellCount(), 0u);
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        const RenderSettings s = frameOf(kept.bounds(), method);
        const RenderResult x = a.render(s), y = b.render(s);
        ASSERT_EQ(x.image.pixels.size(), y.image.pixels.size());
        EXPECT_EQ(0, std::memcmp(x.image.pixels.data(), y.image.pixels.data(),
                                 x.image.pixels.size() * sizeof(Vec4f)))
            << int(method);
    }
}

TEST(Renderer, AMethodWhoseStructuresWereNotPreparedIsRefused) {
    const Mesh m = testing::jitteredHexGrid(10);
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
    const Mesh m = testing::jitteredHexGrid(10);
    RendererOptions o;
    o.device = Device::Cuda;
    EXPECT_EQ(catchError([&] { Renderer r(m, selectScalarField(m, {}), o); }).kind(),
              ErrorKind::Unsupported);
}

TEST(Renderer, OnTheGpuFramesMatchTheCpu) {
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    const Mesh m = testing::jitteredHexGrid(10);
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

/// A jittered grid with a point field "f" and a cell field "c" at time t, and one flat tetrahedron
/// (no tetrahedra kept) between the hexahedra, so a cell field's values must skip it.
Mesh timeStep(float t) {
    Mesh m = testing::makeHexGrid(
        8, -1.f, 1.f, [t](Vec3f p) { return std::sin(3.f * p.x + t) * p.y + t * p.z; }, 0.3f);
    const std::uint32_t flat[4] = {0, 0, 1, 2};
    m.addCell(CellType::Tetra, flat);
    Field c{"c", Association::Cell, 1, {}};
    for (std::uint64_t i = 0; i < m.cellCount(); ++i)
        c.values.push_back(std::cos(0.1f * float(i) + t));
    m.fields.push_back(c);
    return m;
}

/// Bitwise equality of two float arrays (NaN equal to NaN, -0 unequal to +0).
/// Every pixel of two frames equal, bit for bit.
void expectSameFrames(const RenderResult& a, const RenderResult& b, const std::string& what) {
    ASSERT_EQ(a.image.pixels.size(), b.image.pixels.size()) << what;
    EXPECT_EQ(a.stats.samples, b.stats.samples) << what;
    EXPECT_TRUE(testing::sameBytes(a.image.pixels, b.image.pixels)) << what;
    EXPECT_TRUE(testing::sameBytes(a.sampleCounts, b.sampleCounts)) << what;
}

TEST(Renderer, OnTheGpuAutoRendersTheReferenceWhereAdaptiveSavesTooLittle) {
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    // 10^3 native hexahedra: 40 cells per ray, so adaptive rather than exact. With a cell field
    // every visible partition steps at s1 (a jump at every face): adaptive saves nothing, and
    // the reference renders, the explicit reference's frame bit for bit. A linear point field
    // lets adaptive step 16x longer: it renders.
    Mesh m = testing::makeHexGrid(10, 0.f, 10.f, [](Vec3f p) { return 0.1f * p.x; });
    Field c{"c", Association::Cell, 1, {}};
    for (std::uint64_t i = 0; i < m.cellCount(); ++i) c.values.push_back(float(i % 7) / 6.f);
    m.fields.push_back(c);
    RendererOptions o;
    o.device = Device::Cuda;
    o.partitions = o.meshBvh = false;
    o.forAuto = true;
    Renderer cells(m, selectScalarField(m, parseFieldSpec("c")), o);
    ASSERT_EQ(cells.prepared().autoChoice->method, RenderMethod::Partitions);
    RenderSettings s = frameOf(m.bounds(), RenderMethod::Auto);
    const RenderResult a = cells.render(s);
    EXPECT_EQ(a.setup.method.method, RenderMethod::Reference);
    EXPECT_THAT(a.setup.method.reason, HasSubstr("reference: under this transfer function"));
    s.method = RenderMethod::Reference;
    expectSameFrames(a, cells.render(s), "auto against the reference");
    Renderer linear(m, selectScalarField(m, {}), o);
    s.method = RenderMethod::Auto;
    const RenderResult b = linear.render(s);
    EXPECT_EQ(b.setup.method.method, RenderMethod::Partitions);
    EXPECT_THAT(b.setup.method.reason, HasSubstr("adaptive: under this transfer function"));
}

TEST(Renderer, SetFieldValuesGivesTheFramesOfAFreshPreparationWithoutRebuilding) {
    for (const char* spec : {"f", "c"}) {
        const Mesh m0 = timeStep(0.f);
        Mesh m1 = timeStep(0.7f);
        // A NaN in the new values (NaN flags appear) for the point field.
        if (spec[0] == 'f') m1.fields[0].values[100] = NAN;
        const ScalarField f0 = selectScalarField(m0, parseFieldSpec(spec));
        const ScalarField f1 = selectScalarField(m1, parseFieldSpec(spec));
        RendererOptions o;
        o.device = Device::Cpu;
        o.leafCells = 64;
        Renderer r(m0, f0, o);
        const PreparedMesh& p = r.prepared();
        ASSERT_TRUE(p.kd && p.seeds && p.macro);
        // The geometric structures: their contents and their memory, before the update.
        const PreparedMesh before = prepareMesh(m0, f0, o.prepareOptions());
        const void* addresses[] = {p.tets.tets.data(),      p.tets.points.data(),
                                   p.bvh.nodes.data(),      p.neighbors.data(),
                                   p.kd->nodes.data(),      p.kd->cells.data(),
                                   p.cellTree.nodes.data(), p.seeds->seeds.data(),
                                   p.macro->grids.data(),   p.macro->cells.data()};
        const double buildSeconds = p.kd->buildSeconds;
        r.setFieldValues(f1);
        EXPECT_EQ(p.valueUpdates, 1u);
        EXPECT_GE(p.valueUpdateSeconds, 0.0);
        const void* after[] = {p.tets.tets.data(),      p.tets.points.data(),
                               p.bvh.nodes.data(),      p.neighbors.data(),
                               p.kd->nodes.data(),      p.kd->cells.data(),
                               p.cellTree.nodes.data(), p.seeds->seeds.data(),
                               p.macro->grids.data(),   p.macro->cells.data()};
        for (std::size_t i = 0; i < std::size(addresses); ++i)
            EXPECT_EQ(addresses[i], after[i]) << spec << ": array " << i << " was reallocated";
        EXPECT_EQ(p.kd->buildSeconds, buildSeconds);
        EXPECT_TRUE(testing::sameBytes(p.tets.tets, before.tets.tets));
        EXPECT_TRUE(testing::sameBytes(p.bvh.nodes, before.bvh.nodes));
        EXPECT_TRUE(testing::sameBytes(p.kd->cells, before.kd->cells));
        EXPECT_TRUE(testing::sameBytes(p.cellTree.nodes, before.cellTree.nodes));
        EXPECT_TRUE(testing::sameBytes(p.tets.tetCorners, before.tets.tetCorners));
        EXPECT_TRUE(testing::sameBytes(p.neighborCodes.tetCodes, before.neighborCodes.tetCodes));
        EXPECT_TRUE(testing::sameBytes(p.seeds->seeds, before.seeds->seeds));
        // The value-dependent structures equal a fresh preparation's, bit for bit.
        const PreparedMesh fresh = prepareMesh(m1, f1, o.prepareOptions());
        EXPECT_TRUE(testing::sameBytes(p.tets.values, fresh.tets.values)) << spec;
        EXPECT_TRUE(testing::sameBytes(p.tets.blockVertices, fresh.tets.blockVertices)) << spec;
        EXPECT_EQ(p.tets.valueMin, fresh.tets.valueMin) << spec;
        EXPECT_EQ(p.tets.valueMax, fresh.tets.valueMax) << spec;
        EXPECT_TRUE(testing::sameBytes(p.kd->partitions, fresh.kd->partitions)) << spec;
        EXPECT_TRUE(testing::sameBytes(p.gradientSpread, fresh.gradientSpread)) << spec;
        EXPECT_TRUE(testing::sameBytes(p.partitionNan, fresh.partitionNan)) << spec;
        EXPECT_TRUE(testing::sameBytes(p.macro->cells, fresh.macro->cells)) << spec;
        EXPECT_TRUE(testing::sameBytes(p.macro->nanCells, fresh.macro->nanCells)) << spec;
        EXPECT_EQ(p.partitionNan.empty(), spec[0] == 'c') << spec;
        EXPECT_FALSE(testing::sameBytes(p.tets.values, before.tets.values)) << spec;
        for (RenderMethod method :
             {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
            RenderSettings s = frameOf(m0.bounds(), method);
            s.tf.nanOpacity = 0.5f;  // NaN regions visible: the NaN flags matter
            expectSameFrames(r.render(s), renderCpu(fresh, s),
                             std::string(spec) + ", method " + std::to_string(int(method)));
        }
    }
}

TEST(Renderer, SetFieldValuesRefusesTheWrongCountAndChangesNothing) {
    const Mesh m = timeStep(0.f);
    RendererOptions o;
    o.device = Device::Cpu;
    Renderer r(m, selectScalarField(m, parseFieldSpec("f")), o);
    const std::vector<float> values = r.prepared().tets.values;
    ScalarField bad{"f", Association::Point, std::vector<float>(m.pointCount() - 1, 1.f)};
    const Error e = catchError([&] { r.setFieldValues(bad); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr(std::to_string(m.pointCount() - 1) +
                                    " point values, "
                                    "expected " +
                                    std::to_string(m.pointCount())));
    bad.association = Association::Cell;
    bad.values.assign(m.cellCount() + 1, 0.f);
    EXPECT_THAT(catchError([&] { r.setFieldValues(bad); }).what(),
                HasSubstr("expected " + std::to_string(m.cellCount())));
    EXPECT_EQ(r.prepared().valueUpdates, 0u);
    EXPECT_TRUE(testing::sameBytes(r.prepared().tets.values, values));
    // Another field of the same mesh, of the other association, is fine.
    r.setFieldValues(selectScalarField(m, parseFieldSpec("c")));
    EXPECT_EQ(r.prepared().tets.association, Association::Cell);
    EXPECT_EQ(r.prepared().tets.values.size(), r.prepared().tets.cellCount());
}

TEST(Renderer, OnTheGpuSetFieldValuesGivesTheFramesOfAFreshUpload) {
    if (!cudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device: " << cudaDeviceDescription();
    const Mesh m0 = timeStep(0.f), m1 = timeStep(0.7f);
    const ScalarField f0 = selectScalarField(m0, parseFieldSpec("f"));
    ScalarField f1 = selectScalarField(m1, parseFieldSpec("f"));
    f1.values[100] = NAN;
    RendererOptions o;
    o.device = Device::Cuda;
    o.leafCells = 64;
    Renderer updated(m0, f0, o);
    const std::uint64_t bytes = updated.gpuResidency()->geometryBytes;
    updated.setFieldValues(f1);
    EXPECT_EQ(
        updated.gpuResidency()->geometryBytes,
        bytes + updated.prepared().partitionNan.size() + updated.prepared().macro->nanCells.size());
    EXPECT_GT(updated.gpuResidency()->valueUploadSeconds, 0.0);
    Renderer fresh(m1, f1, o);
    for (RenderMethod method :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        RenderSettings s = frameOf(m0.bounds(), method);
        s.tf.nanOpacity = 0.5f;
        expectSameFrames(updated.render(s), fresh.render(s),
                         "method " + std::to_string(int(method)));
    }
}

}  // namespace
}  // namespace uvr

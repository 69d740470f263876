// SPDX-License-Identifier: MIT
#include "uvr/prepare/render_method.h"

#include <gmock/gmock.h>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/facade/renderer.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

/// A k x k x k grid of unit-spaced hexahedra over [0, k]^3, native or split into tetrahedra.
PreparedMesh hexGrid(int k, bool split = false, const PrepareOptions& base = {}) {
    const Mesh m =
        testing::makeHexGrid(k, 0.f, float(k), [](Vec3f p) { return p.x + 2.f * p.y - p.z; });
    PrepareOptions o = base;
    o.cells.splitCells = split;
    return prepareMesh(m, selectScalarField(m, {}), o);
}

TEST(RenderMethod, NamesRoundTripAndTheDefaultIsAutoListedFirst) {
    for (const MethodName& m : kMethods) {
        EXPECT_STREQ(methodName(m.method), m.name);
        ASSERT_TRUE(parseMethod(m.name));
        EXPECT_EQ(*parseMethod(m.name), m.method);
    }
    EXPECT_FALSE(parseMethod("fast"));
    EXPECT_FALSE(parseMethod("Adaptive"));
    EXPECT_EQ(kMethods[0].method, RenderSettings{}.method);
    EXPECT_EQ(RenderSettings{}.method, RenderMethod::Auto);
    EXPECT_EQ(methodNames(), (std::vector<std::string>{"auto", "adaptive", "reference", "exact"}));
}

TEST(RenderMethod, CellsPerRayOfAGridOfCubesIsItsSide) {
    // Cauchy's formula, exactly: k^3 cubes of surface 6 over a box of surface 6 k^2 give k, the
    // cells a ray parallel to an axis crosses. A native cell counts its cost; the split counts
    // the tetrahedra's own faces, inner ones included, so more.
    for (int k : {1, 3, 7}) {
        const PreparedMesh native = hexGrid(k);
        EXPECT_NEAR(exactCellsPerRay(native.tets, 1.0), k, 1e-4 * k) << k;
        EXPECT_NEAR(exactCellsPerRay(native.tets, 4.0), 4.0 * k, 4e-4 * k) << k;
        const PreparedMesh split = hexGrid(k, /*split=*/true);
        EXPECT_GT(exactCellsPerRay(split.tets, 4.0), 1.5 * k) << k;  // cost 4 is for native only
        EXPECT_LT(exactCellsPerRay(split.tets, 4.0), 4.0 * k) << k;
    }
    // Past kAutoSampleCells cells the estimate samples: 48^3 = 110,592 cubes, still 48.
    EXPECT_NEAR(exactCellsPerRay(hexGrid(48).tets, 1.0), 48.0, 0.05);
    EXPECT_EQ(exactCellsPerRay(TetMesh{}, 1.0), 0.0);
}

TEST(RenderMethod, CellsPerRayIsTheMeanCrossingsOfAnExactFrame) {
    // What the rule estimates is what the exact integrator does: parallel rays face-on through
    // the 6^3 grid cross exactly 6 cells each.
    const PreparedMesh pm = hexGrid(6);
    RenderSettings s;
    s.method = RenderMethod::Exact;
    s.tf = transferFunctionPreset("viridis");
    s.terminationAlpha = 1.f;  // every crossing counts
    s.width = s.height = 24;
    Camera c = resetCamera(pm.tets.bounds, 1.f);
    c.parallelProjection = true;
    c.parallelScale = 2.f;  // inside the grid's face: every ray crosses it
    s.camera = c;
    const RenderResult r = renderCpu(pm, s);
    EXPECT_NEAR(r.stats.meanSamplesPerRay(), exactCellsPerRay(pm.tets, 1.0), 0.05);
}

TEST(RenderMethod, AutoPicksExactForFewCellsPerRayByTheDevicesLimits) {
    // 6 native hexahedra a side: 6 x 4 = 24 <= 32; 10: 40 > 32 (both devices measure 32 today).
    const AutoMethodChoice small = autoMethod(hexGrid(6).tets, /*gpu=*/false);
    EXPECT_EQ(small.method, RenderMethod::Exact);
    EXPECT_NEAR(small.cellsPerRay, 24.0, 1e-3);
    EXPECT_EQ(small.reason(), "auto: exact (about 24 cells per ray, at most 32 on the CPU)");
    const PreparedMesh ten = hexGrid(10);
    const AutoMethodChoice cpu = autoMethod(ten.tets, false), gpu = autoMethod(ten.tets, true);
    EXPECT_EQ(cpu.method, RenderMethod::Partitions);
    EXPECT_EQ(cpu.reason(), "auto: adaptive (about 40 cells per ray, more than 32 on the CPU)");
    EXPECT_EQ(gpu.method, RenderMethod::Partitions);
    EXPECT_TRUE(gpu.gpu);
    EXPECT_EQ(gpu.reason(), "auto: adaptive (about 40 cells per ray, more than 32 on the GPU)");
    EXPECT_EQ(autoMethod(hexGrid(6).tets, true).method, RenderMethod::Exact);
    // Split into tetrahedra, a crossing costs one.
    EXPECT_EQ(autoMethod(hexGrid(10, true).tets, false).method, RenderMethod::Exact);
}

TEST(RenderMethod, PreparingForAutoBuildsOnlyWhatItsPickRendersWith) {
    PrepareOptions o;
    o.meshBvh = o.partitions = false;
    o.forAuto = true;
    const PreparedMesh exact = hexGrid(4, false, o), adaptive = hexGrid(12, false, o);
    ASSERT_TRUE(exact.autoChoice && adaptive.autoChoice);
    EXPECT_EQ(exact.autoChoice->method, RenderMethod::Exact);
    EXPECT_FALSE(exact.bvh.nodes.empty());
    EXPECT_FALSE(exact.kd);
    EXPECT_EQ(adaptive.autoChoice->method, RenderMethod::Partitions);
    EXPECT_TRUE(adaptive.bvh.nodes.empty());
    EXPECT_TRUE(adaptive.kd);
    // Auto renders them so: exact's frame is the explicit exact frame, bit for bit.
    RenderSettings s;
    s.width = s.height = 32;
    s.tf = transferFunctionPreset("viridis");
    const RenderResult a = renderCpu(exact, s);
    EXPECT_EQ(a.setup.method.method, RenderMethod::Exact);
    EXPECT_THAT(a.setup.method.reason, HasSubstr("auto: exact"));
    s.method = RenderMethod::Exact;
    const RenderResult e = renderCpu(exact, s);
    EXPECT_TRUE(testing::sameBytes(a.image.pixels, e.image.pixels));
    EXPECT_TRUE(e.setup.method.reason.empty());
    s.method = RenderMethod::Auto;
    EXPECT_EQ(renderCpu(adaptive, s).setup.method.method, RenderMethod::Partitions);
}

TEST(RenderMethod, OnTheGpuAutoPreparesTheReferenceToWeighEachFrame) {
    // Where the GPU's auto picks adaptive, an adaptive sample costs 2x a reference sample there:
    // both structures are prepared, and each frame weighs the two. Not on the CPU.
    EXPECT_EQ(kAutoCpuLimits.adaptiveSampleCost, 0.0);
    EXPECT_EQ(kAutoCpuLimits.nativeAdaptiveSampleCost, 0.0);
    EXPECT_GT(kAutoGpuLimits.adaptiveSampleCost, 1.0);
    EXPECT_GT(kAutoGpuLimits.nativeAdaptiveSampleCost, 1.0);
    PrepareOptions o;
    o.meshBvh = o.partitions = false;
    o.forAuto = true;
    o.autoOnGpu = true;
    const PreparedMesh gpu = hexGrid(12, false, o);
    ASSERT_TRUE(gpu.autoChoice);
    EXPECT_EQ(gpu.autoChoice->method, RenderMethod::Partitions);
    // Native hexahedra weigh at their cost; split into tetrahedra, at the tetrahedra's.
    EXPECT_EQ(gpu.autoChoice->adaptiveSampleCost, kAutoGpuLimits.nativeAdaptiveSampleCost);
    const AutoMethodChoice split = autoMethod(hexGrid(24, /*split=*/true).tets, true);
    EXPECT_EQ(split.method, RenderMethod::Partitions);
    EXPECT_EQ(split.adaptiveSampleCost, kAutoGpuLimits.adaptiveSampleCost);
    EXPECT_FALSE(gpu.bvh.nodes.empty());
    EXPECT_TRUE(gpu.kd);
    RenderSettings s;
    EXPECT_EQ(resolveMethod(gpu, s, /*gpu=*/true).weighReference,
              kAutoGpuLimits.nativeAdaptiveSampleCost);
    EXPECT_EQ(resolveMethod(gpu, s, /*gpu=*/false).weighReference, 0.0);
    // Exact picked, or sampling tuned, or the method named: nothing is weighed.
    EXPECT_EQ(autoMethod(hexGrid(4).tets, true).adaptiveSampleCost, 0.0);
    s.quality = 0.999f;
    EXPECT_EQ(resolveMethod(gpu, s, true).weighReference, 0.0);
    s = {};
    s.method = RenderMethod::Partitions;
    EXPECT_EQ(resolveMethod(gpu, s, true).weighReference, 0.0);
    // Without the mesh BVH (a cache of an older preparation) there is nothing to weigh.
    PrepareOptions k;
    k.meshBvh = false;
    EXPECT_EQ(resolveMethod(hexGrid(12, false, k), RenderSettings{}, true).weighReference, 0.0);
    // On the CPU auto prepares the partitions alone, as before.
    o.autoOnGpu = false;
    const PreparedMesh cpu = hexGrid(12, false, o);
    EXPECT_EQ(cpu.autoChoice->adaptiveSampleCost, 0.0);
    EXPECT_TRUE(cpu.bvh.nodes.empty());
}

TEST(RenderMethod, EstimatedSamplesArePerVolumeAtEachPartitionsStep) {
    KdPartitions kd;
    kd.partitions.resize(3);
    kd.partitions[0].box = {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}};  // volume 1
    kd.partitions[1].box = {{1.f, 0.f, 0.f}, {4.f, 1.f, 1.f}};  // volume 3
    kd.partitions[2].box = {{4.f, 0.f, 0.f}, {6.f, 1.f, 1.f}};  // volume 2
    std::vector<PartitionShading> shading{{1.f, 0.5f}, {0.f, 8.f}, {1.f, 0.25f, true}};
    // p0 at 1 / 0.5, p1 skipped, p2 by its macrocells at 3 a unit; the reference 1 / 0.25 in all.
    SampleEstimate e = estimateSamples(kd, shading, {0.f, 0.f, 3.f}, 0.25f);
    EXPECT_DOUBLE_EQ(e.adaptive, 1.0 * 2.0 + 2.0 * 3.0);
    EXPECT_DOUBLE_EQ(e.reference, 6.0 * 4.0);
    EXPECT_DOUBLE_EQ(e.finer, 0.0);  // no visible partition steps below s1
    // Without the macrocells' densities p2 counts its own step.
    e = estimateSamples(kd, shading, {}, 0.25f);
    EXPECT_DOUBLE_EQ(e.adaptive, 1.0 * 2.0 + 2.0 * 4.0);
    // Steps below s1 count where the partition is visible (p0), not where it is skipped (p1).
    shading[0].step = shading[1].step = 0.125f;
    e = estimateSamples(kd, shading, {}, 0.25f);
    EXPECT_DOUBLE_EQ(e.adaptive, 1.0 * 8.0 + 2.0 * 4.0);
    EXPECT_DOUBLE_EQ(e.finer, 1.0);
    // A flat partition has no volume to sample.
    kd.partitions[0].box.hi.z = 0.f;
    EXPECT_DOUBLE_EQ(estimateSamples(kd, shading, {}, 0.25f).reference, 5.0 * 4.0);
    EXPECT_THROW(estimateSamples(kd, {}, {}, 0.25f), Error);
}

TEST(RenderMethod, WeighingPicksTheReferenceWhereAdaptiveSavesLessThanItsSampleCosts) {
    PrepareOptions o;
    o.forAuto = true;
    o.autoOnGpu = true;
    const PreparedMesh pm = hexGrid(12, false, o);
    RenderSettings s;
    s.width = s.height = 16;
    s.tf = transferFunctionPreset("viridis");
    s.method = RenderMethod::Partitions;  // the shading auto weighs with
    // A linear field: no partition needs a step below s2, so adaptive saves s2 / s1 = 16x.
    FrameSetup f = makeFrameSetup(pm, s, /*gpu=*/false);
    f.method.weighReference = 2.0;
    weighReference(f, pm, {}, /*gpu=*/true);
    EXPECT_EQ(f.method.method, RenderMethod::Partitions);
    EXPECT_EQ(f.method.weighReference, 0.0);
    EXPECT_THAT(f.method.reason, HasSubstr("adaptive: under this transfer function adaptive would "
                                           "take 16x fewer samples than the reference, at least "
                                           "the 2x its sample costs on the GPU"));
    // Every partition at s1: nothing saved, the reference renders.
    s.adaptive = false;
    f = makeFrameSetup(pm, s, false);
    f.method.weighReference = 2.0;
    weighReference(f, pm, {}, false);
    EXPECT_EQ(f.method.method, RenderMethod::Reference);
    EXPECT_THAT(f.method.reason, HasSubstr("reference: under this transfer function adaptive "
                                           "would take 1x fewer samples than the reference, "
                                           "under the 2x its sample costs on the CPU"));
    // A partition whose error bound asks for less than s1: the reference would be less right,
    // so adaptive renders whatever the samples.
    f = makeFrameSetup(pm, s, false);
    ASSERT_GT(f.shading.size(), 1u);
    f.shading[0].step = 0.5f * f.stepRule.s1;
    f.method.weighReference = 2.0;
    weighReference(f, pm, {}, true);
    EXPECT_EQ(f.method.method, RenderMethod::Partitions);
    EXPECT_THAT(f.method.reason, HasSubstr("adaptive: under this transfer function its error "
                                           "bound asks for steps below s1 in "));
    EXPECT_THAT(f.method.reason, HasSubstr("which the reference's s1 would miss"));
    // Nothing visible: adaptive skips it all.
    s.adaptive = true;
    s.tf.opacities = {{0.f, 0.f}, {1.f, 0.f}};
    f = makeFrameSetup(pm, s, false);
    f.method.weighReference = 2.0;
    weighReference(f, pm, {}, true);
    EXPECT_EQ(f.method.method, RenderMethod::Partitions);
    EXPECT_THAT(f.method.reason, HasSubstr("take no samples"));
    // Not asked to weigh: unchanged.
    s.adaptive = false;
    f = makeFrameSetup(pm, s, false);
    weighReference(f, pm, {}, true);
    EXPECT_EQ(f.method.method, RenderMethod::Partitions);
    EXPECT_TRUE(f.method.reason.empty());
}

TEST(RenderMethod, AutoFollowsSamplingSettingsAndWhatWasPrepared) {
    const PreparedMesh both = hexGrid(4);  // the default preparation: both structures
    RenderSettings s;
    EXPECT_EQ(resolveMethod(both, s, false).method, RenderMethod::Exact);
    // A setting only the sampling methods read makes auto the adaptive method it tunes.
    const auto tuned = [&](auto change) {
        RenderSettings t;
        change(t);
        EXPECT_TRUE(tunesAdaptive(t));
        const ResolvedMethod r = resolveMethod(both, t, false);
        EXPECT_EQ(r.method, RenderMethod::Partitions);
        EXPECT_THAT(r.reason, HasSubstr("tune its sampling"));
    };
    tuned([](RenderSettings& t) { t.quality = 0.999f; });
    tuned([](RenderSettings& t) { t.step = 0.1f; });
    tuned([](RenderSettings& t) { t.maxStep = 1.f; });
    tuned([](RenderSettings& t) { t.preintegrated = false; });
    tuned([](RenderSettings& t) { t.stepRule = StepRule::Variance; });
    tuned([](RenderSettings& t) { t.power = 3.f; });
    tuned([](RenderSettings& t) { t.skip = false; });
    tuned([](RenderSettings& t) { t.adaptive = false; });
    EXPECT_FALSE(tunesAdaptive(RenderSettings{}));
    // Without the structures of its pick, the other of exact and adaptive, and it says so.
    PrepareOptions o;
    o.meshBvh = false;
    const ResolvedMethod noBvh = resolveMethod(hexGrid(4, false, o), s, false);
    EXPECT_EQ(noBvh.method, RenderMethod::Partitions);
    EXPECT_THAT(noBvh.reason, HasSubstr("the mesh BVH exact needs was not prepared"));
    o = {};
    o.partitions = false;
    const ResolvedMethod noKd = resolveMethod(hexGrid(12, false, o), s, false);
    EXPECT_EQ(noKd.method, RenderMethod::Exact);
    EXPECT_THAT(noKd.reason, HasSubstr("the partitions adaptive needs were not prepared"));
    // A method asked for by name is rendered as asked.
    for (RenderMethod m :
         {RenderMethod::Partitions, RenderMethod::Reference, RenderMethod::Exact}) {
        s.method = m;
        EXPECT_EQ(resolveMethod(both, s, false).method, m);
    }
}

TEST(RenderMethod, TheRendererDecidesForItsDevice) {
    const Mesh m = testing::makeHexGrid(10, 0.f, 10.f, [](Vec3f p) { return p.x; });
    RendererOptions o;
    o.device = Device::Cpu;
    o.partitions = o.meshBvh = false;
    o.forAuto = true;
    Renderer r(m, selectScalarField(m, {}), o);
    ASSERT_TRUE(r.prepared().autoChoice);
    EXPECT_FALSE(r.prepared().autoChoice->gpu);
    EXPECT_EQ(r.prepared().autoChoice->method, RenderMethod::Partitions);  // 40 > 32
    RenderSettings s;
    s.tf = transferFunctionPreset("viridis");
    s.width = s.height = 16;
    EXPECT_EQ(r.render(s).setup.method.method, RenderMethod::Partitions);
}

}  // namespace
}  // namespace uvr

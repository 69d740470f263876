// SPDX-License-Identifier: MIT
// Pre-integrated sampling and the error-bound step rule (issue 11, sections 2 and 3), held to
// the exact integrator: a transfer-function band between two samples, linear fields at long
// steps, the rule's ends and its gradient metadata, and the rule against exact on a smooth field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "on_each_device.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

/// A unit cube of 4^3 hexahedra (jittered inside) with the point field f, partitions of at most
/// leafCells tetrahedra.
PreparedMesh cube(const std::function<float(Vec3f)>& f, std::uint32_t leafCells = 64, int n = 4) {
    const Mesh m = testing::makeHexGrid(n, 0.f, 1.f, f, 0.2f);
    PrepareOptions o;
    o.kd.leafCells = leafCells;
    return prepareMesh(m, selectScalarField(m, {}), o);
}

/// Looking down the z axis at the cube, field range [0, 1], opacity only in a band of the
/// normalised range.
RenderSettings bandSettings(const char* opacity, float step) {
    RenderSettings s;
    s.method = RenderMethod::Reference;
    s.width = s.height = 24;
    s.camera = Camera{};
    s.camera->position = Vec3f(0.5f, 0.5f, 3.f);
    s.camera->focalPoint = Vec3f(0.5f, 0.5f, 0.5f);
    s.camera->viewUp = Vec3f(0.f, 1.f, 0.f);
    s.camera->viewAngle = 20.f;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, opacity);
    s.range = std::pair{0.f, 1.f};
    s.step = step;
    s.opacityUnit = 0.1f;
    s.terminationAlpha = 1.f;
    return s;
}

/// Preintegration's frames render on every device (tests/on_each_device.h).
class Preintegration : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Preintegration);

/// OpacityLawFrames's frames render on every device (tests/on_each_device.h).
class OpacityLawFrames : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(OpacityLawFrames);

/// ErrorBoundRule's frames render on every device (tests/on_each_device.h).
class ErrorBoundRule : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(ErrorBoundRule);

/// MacroCells's frames render on every device (tests/on_each_device.h).
class MacroCells : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(MacroCells);

TEST_P(Preintegration, BandBetweenTwoSamplesIsIntegratedNotMissed) {
    // v = z, samples 0.1 apart along the central ray at z = 3 - 0.1 k: the band [0.52, 0.58]
    // lies between the samples at z = 0.5 and 0.6. Point samples miss it; pre-integration is
    // exact for a linear field (the tails beyond the band are transparent).
    const PreparedMesh pm = cube([](Vec3f p) { return p.z; });
    RenderSettings s = bandSettings("0:0,0.52:0,0.53:0.8,0.57:0.8,0.58:0,1:0", 0.1f);
    RenderSettings e = s;
    e.method = RenderMethod::Exact;
    const RenderResult exact = render(pm, e);
    const Vec4f centre = exact.image.at(12, 12);
    EXPECT_GT(centre.w, 0.3f);  // 0.05 through the band at 0.8 per 0.1: about 0.6
    s.preintegrated = false;
    EXPECT_LT(render(pm, s).image.at(12, 12).w, 0.05f);  // missed or nearly
    s.preintegrated = true;
    const RenderResult ref = render(pm, s);
    EXPECT_LT(testing::maxPixelDifference(ref.image, exact.image), 2e-4f);
    // The partition method too, at every rule (the variance rule's steps are up to 16 s1).
    s.method = RenderMethod::Partitions;
    for (const StepRule rule : {StepRule::ErrorBound, StepRule::Variance}) {
        s.stepRule = rule;
        EXPECT_LT(testing::maxPixelDifference(render(pm, s).image, exact.image), 2e-4f);
    }
}

TEST_P(Preintegration, LinearFieldGetsTheLongestStepsAndStaysExact) {
    // A linear field has no gradient spread: the error-bound rule gives every visible partition
    // s2, and pre-integration along linear segments (and the runs' last slopes) is still exact.
    const PreparedMesh pm = cube([](Vec3f p) { return 0.3f * p.x + 0.5f * p.y + p.z; }, 64, 6);
    RenderSettings s = bandSettings("0:0,0.3:0.6,0.35:0,0.6:0,0.7:0.8,0.8:0,1:0.2", 0.02f);
    s.range = std::pair{0.f, 1.8f};
    RenderSettings e = s;
    e.method = RenderMethod::Exact;
    const RenderResult exact = render(pm, e);
    s.method = RenderMethod::Partitions;
    s.maxStep = 0.3f;  // 15 s1
    const RenderResult a = render(pm, s);
    for (const PartitionShading& sh : a.setup.shading) {
        if (sh.maxOpacity > 0.f) {
            EXPECT_FLOAT_EQ(sh.step, 0.3f);
        }
    }
    s.method = RenderMethod::Reference;
    const RenderResult r = render(pm, s);
    // (Both take a sample where each run starts and ends at the mesh's boundary.)
    EXPECT_LT(a.stats.samples * 5, r.stats.samples * 2);
    // Inside the mesh both are exact, and their runs start and end at the mesh's boundary
    // (sampleAtBoundary), so both give exact's image.
    EXPECT_LT(testing::maxPixelDifference(a.image, r.image), 1e-3f);
    EXPECT_LT(testing::maxPixelDifference(r.image, exact.image), 1e-3f);
    EXPECT_LT(testing::maxPixelDifference(a.image, exact.image), 1e-3f);
    EXPECT_GT(compareImages(toRgb8(exact.image), toRgb8(r.image)).ssim, 0.99);
}

TEST(PreintegrationMath, FastPiecesMatchTheClosedForm) {
    // The sample-based methods' float pieces against the exact integrator's double ones: within
    // 1e-3 at every optical depth (deep pieces fall back), with opacities of 0, near 1 and 1 at
    // either end, nearly equal ends, and from any accumulated opacity.
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    auto opacity = [&] {
        const float r = u(rng);
        if (r < 0.15f) return 0.f;
        if (r < 0.25f) return 1.f;
        if (r < 0.4f) return 1.f - 1e-3f * u(rng);
        return u(rng);
    };
    for (int i = 0; i < 50000; ++i) {
        const OpacityLaw law = i % 2 ? OpacityLaw::Transmittance : OpacityLaw::Attenuation;
        const Vec3f c0(u(rng), u(rng), u(rng)), c1(u(rng), u(rng), u(rng));
        const float a0 = opacity();
        const float a1 = u(rng) < 0.1f ? a0 * (1.f + 1e-4f * u(rng)) : opacity();
        const float len = 0.01f + (u(rng) < 0.5f ? 2.f : 40.f) * u(rng), unit = 0.1f + u(rng);
        const float start = u(rng) < 0.5f ? 0.f : u(rng);
        Vec4f fast(0.1f * start, 0.2f * start, 0.3f * start, start), slow = fast;
        segment::compositePieceFast(c0, a0, c1, a1, len, unit, law, fast);
        segment::compositePiece(c0, a0, c1, a1, len, unit, law, slow);
        for (int c = 0; c < 4; ++c)
            ASSERT_NEAR(fast[c], slow[c], 1e-3f)
                << opacityLawName(law) << " " << a0 << " " << a1 << " " << len / unit;
    }
}

/// Per pixel, the largest difference of the 8-bit premultiplied colours over black (0..255), in
/// increasing order.
std::vector<int> sortedPixelDifferences(const Image& a, const Image& b) {
    const Rgb8Image x = toRgb8(a), y = toRgb8(b);
    std::vector<int> d(x.rgb.size() / 3, 0);
    for (std::size_t i = 0; i < d.size(); ++i)
        for (int c = 0; c < 3; ++c)
            d[i] = std::max(d[i], std::abs(int(x.rgb[3 * i + c]) - int(y.rgb[3 * i + c])));
    std::sort(d.begin(), d.end());
    return d;
}

// tetraMesh.vtk at the command line's defaults (cool to warm, the opacity ramp reaching 1 at the
// field's maximum, ParaView's opacity unit): under the transmittance law an opacity of 1 is a
// wall, and whether a ray's sample or segment lands on the field's maximum on the faces decides
// between opaque and not (banding, dark dots, white dashes; 177/255 between methods, issue 29).
// Under the default attenuation law it is an extinction like any other: every method agrees
// with exact to the bounds (99.9th percentile <= 4/255, maximum <= 24/255).
TEST_P(OpacityLawFrames, TetraMeshOpacityOneAgreesWithExactInEveryMethod) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const Mesh mesh = readMesh(testing::sharedData("tetraMesh.vtk"));
    const PreparedMesh pm = prepareMesh(mesh, selectScalarField(mesh, {}));
    for (const auto& [azimuth, elevation] : {std::pair{0.f, 0.f}, std::pair{35.f, 25.f}}) {
        RenderSettings s;
        s.width = s.height = 128;
        s.tf = transferFunctionPreset("cool-to-warm");
        applyOpacitySpec(s.tf, "ramp");
        s.camera = orbitCamera(resetCamera(pm.tets.bounds, 1.f), azimuth, elevation);
        s.method = RenderMethod::Exact;
        const RenderResult exact = render(pm, s);
        for (const RenderMethod method : {RenderMethod::Reference, RenderMethod::Partitions}) {
            s.method = method;
            const RenderResult r = render(pm, s);
            const std::vector<int> d = sortedPixelDifferences(exact.image, r.image);
            const std::string what =
                std::string(method == RenderMethod::Reference ? "reference" : "adaptive") +
                " at azimuth " + std::to_string(int(azimuth));
            EXPECT_LE(d[d.size() * 999 / 1000], 4) << what;
            EXPECT_LE(d.back(), 24) << what;
        }
    }
}

TEST(ErrorBoundStep, EndsAndFormula) {
    StepRuleParams r;
    r.s1 = 0.01f;
    r.s2 = 0.16f;
    r.tolerance = 0.05f;
    r.valuePerEntry = 0.002f;
    EXPECT_EQ(errorBoundStep(0.f, 5.f, r), 0.16f);        // constant transfer function
    EXPECT_EQ(errorBoundStep(0.3f, 0.f, r), 0.16f);       // linear field
    EXPECT_EQ(errorBoundStep(0.3f, INFINITY, r), 0.01f);  // cell-centred field
    EXPECT_EQ(errorBoundStep(NAN, 1.f, r), 0.16f);
    // h = 4 * 0.05 * 0.002 / (0.1 * 0.5) = 0.008 -> s1; with spread 0.05: 0.08.
    EXPECT_EQ(errorBoundStep(0.1f, 0.5f, r), 0.01f);
    EXPECT_NEAR(errorBoundStep(0.1f, 0.05f, r), 0.08f, 1e-6f);
    // Invisible partitions get s2 whatever their rate.
    const RangeStats invisible{0.f, 0.3f, 5.f};
    EXPECT_EQ(shadePartition(invisible, 1.f, 0.f, 1.f, r).step, 0.16f);
    r.adaptive = false;
    EXPECT_EQ(shadePartition(RangeStats{0.5f, 0.3f, 5.f}, 0.f, 0.f, 1.f, r).step, 0.01f);
}

TEST(PartitionGradientSpread, BoundsTheGradientsOfTheCells) {
    // A linear field: every tetrahedron has the same gradient (spread at rounding level). The
    // field x^2: gradients (2x, 0, 0) over the partition's cells, so the spread is about twice
    // the partition's extent in x.
    const PreparedMesh lin = cube([](Vec3f p) { return 2.f * p.x - p.y + 0.5f * p.z; }, 32, 6);
    for (float spread : lin.gradientSpread) EXPECT_LT(spread, 1e-4f);
    // Piecewise-linear gradients of x^2 on tetrahedra of size h = 1/6 err by up to about
    // 2h (more with the jitter) in every component.
    const PreparedMesh quad = cube([](Vec3f p) { return p.x * p.x; }, 32, 6);
    ASSERT_EQ(quad.gradientSpread.size(), quad.kd->partitions.size());
    const float h = 1.f / 6.f;
    for (std::size_t p = 0; p < quad.kd->partitions.size(); ++p) {
        const KdPartition& part = quad.kd->partitions[p];
        if (part.cellCount == 0) continue;
        const float width = part.box.hi.x - part.box.lo.x;
        EXPECT_GT(quad.gradientSpread[p], 2.f * (width - 2.f * h)) << p;
        EXPECT_LT(quad.gradientSpread[p], 2.f * width + 4.f * h) << p;
    }
    // A cell-centred field has no gradient bound.
    Mesh cells = testing::makeHexGrid(3, 0.f, 1.f);
    cells.fields.push_back({"c", Association::Cell, 1, std::vector<float>(27, 1.f)});
    const PreparedMesh cc = prepareMesh(cells, selectScalarField(cells, parseFieldSpec("c")));
    for (float spread : cc.gradientSpread) EXPECT_EQ(spread, INFINITY);
}

TEST_P(ErrorBoundRule, SmoothFieldMeetsTheTargetWithFewerSamples) {
    // A smooth non-linear field under a two-band transfer function: the default quality's rule
    // stays as close to exact as the reference and takes fewer samples; a lower quality takes
    // fewer still.
    const PreparedMesh pm =
        cube([](Vec3f p) { return std::sin(4.f * p.x) * std::cos(3.f * p.y) + p.z; }, 64, 10);
    RenderSettings s;
    s.method = RenderMethod::Reference;
    s.width = s.height = 64;
    s.camera = orbitCamera(resetCamera(pm.tets.bounds, 1.f), 35.f, 25.f);
    s.tf = transferFunctionPreset("cool-to-warm");
    applyOpacitySpec(s.tf, "0:0,0.3:0,0.35:0.7,0.4:0,0.6:0,0.65:0.9,0.7:0,1:0.1");
    RenderSettings e = s;
    e.method = RenderMethod::Exact;
    const Rgb8Image exact = toRgb8(render(pm, e).image);
    const RenderResult ref = render(pm, s);
    s.method = RenderMethod::Partitions;
    const RenderResult good = render(pm, s);
    s.quality = 0.9f;
    const RenderResult rough = render(pm, s);
    // On a mesh of 10^3 cells the reference's step is a 36th of the depth, and where rays enter
    // and leave the mesh its samples own up to a step beyond it: that is most of its difference.
    const double refSsim = compareImages(exact, toRgb8(ref.image)).ssim;
    EXPECT_GE(refSsim, 0.97);
    EXPECT_GE(compareImages(exact, toRgb8(good.image)).ssim, refSsim - 0.005);
    int longer = 0;
    for (const PartitionShading& sh : good.setup.shading)
        longer += sh.maxOpacity > 0.f && sh.step > 1.5f * ref.setup.params.step;
    EXPECT_GT(longer, 0);  // visible partitions with steps beyond s1
    EXPECT_LT(good.stats.samples, ref.stats.samples);
    EXPECT_LT(rough.stats.samples, good.stats.samples);
}

TEST_P(MacroCells, SkipTransparentSpaceAndStepLongWithTheImageOfExact) {
    // A smooth field on the non-convex shell (empty macrocells in its hole, a silhouette all
    // round): under a narrow band most macrocells are transparent and skipped (half the samples
    // or fewer); under ramps (where partitions may keep their own steps) as under the band, the
    // image is the exact integrator's, at an oblique and an edge-on view.
    ProceduralSpec spec;
    spec.shape = ProceduralShape::Shell;
    spec.targetCells = 150000;
    spec.fields = {ProceduralField::Jet};
    const Mesh mesh = generateMesh(spec);
    PrepareOptions o;
    o.kd.leafCells = 4096;
    const PreparedMesh pm = prepareMesh(mesh, selectScalarField(mesh, {}), o);
    o.macroGrids = false;
    const PreparedMesh plain = prepareMesh(mesh, selectScalarField(mesh, {}), o);
    for (const char* opacity : {"0:0,0.49:0,0.5:1,0.51:0,1:0", "0:0.3,1:1", "0:0,1:0.3"})
        for (const float azimuth : {40.f, 90.f}) {
            RenderSettings s;
            s.width = s.height = 96;
            s.camera = orbitCamera(resetCamera(pm.tets.bounds, 1.f), azimuth, 10.f);
            s.tf = transferFunctionPreset("viridis");
            applyOpacitySpec(s.tf, opacity);
            s.method = RenderMethod::Exact;
            const Rgb8Image exact = toRgb8(render(pm, s).image);
            s.method = RenderMethod::Partitions;
            const RenderResult macro = render(pm, s);
            const RenderResult partitions = render(plain, s);
            const std::string what = std::string(opacity) + " at " + std::to_string(azimuth);
            EXPECT_GE(compareImages(exact, toRgb8(macro.image)).ssim, 0.99) << what;
            if (opacity[4] == '0') {  // the band: partitions march by their macrocells
                int byMacro = 0;
                for (const PartitionShading& sh : macro.setup.shading) byMacro += sh.byMacroCells;
                EXPECT_GT(byMacro, 0) << what;
                EXPECT_LT(macro.stats.samples * 2, partitions.stats.samples) << what;
            }
        }
}

TEST(ErrorBoundRuleSetup, QualityOutOfRangeIsRefused) {
    EXPECT_THROW(toleranceForQuality(1.f), Error);
    EXPECT_THROW(toleranceForQuality(0.f), Error);
    EXPECT_THROW(toleranceForQuality(NAN), Error);
    EXPECT_GT(toleranceForQuality(0.9f), toleranceForQuality(0.99f));
}

}  // namespace
}  // namespace uvr

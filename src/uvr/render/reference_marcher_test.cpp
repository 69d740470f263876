// SPDX-License-Identifier: MIT
#include "uvr/render/reference_marcher.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/render/frame_kernel.h"

namespace uvr {
namespace {

/// Two unit cubes of 3^3 hexes at x in [0,1] and [2,3] (a gap between), constant field 1.
Mesh twoCubes() {
    Mesh a = testing::makeHexGrid(3, 0.f, 1.f);
    Mesh b = testing::makeHexGrid(3, 0.f, 1.f);
    const std::uint32_t base = static_cast<std::uint32_t>(a.pointCount());
    for (Vec3f p : b.points) a.points.push_back(p + Vec3f(2.f, 0.f, 0.f));
    for (std::uint64_t c = 0; c < b.cellCount(); ++c) {
        std::uint32_t ids[8];
        for (int k = 0; k < 8; ++k) ids[k] = b.cell(c)[k] + base;
        a.addCell(CellType::Hexahedron, ids);
    }
    a.fields[0].values.resize(a.pointCount(), 1.f);
    return a;
}

struct Fixture {
    PreparedMesh mesh;
    std::vector<Vec4f> table;
    SceneView scene;
    Fixture(const Mesh& m, Vec4f rgba, float step, float unit) {
        mesh = prepareMesh(m, selectScalarField(m, {}));
        table = {rgba, rgba};
        scene.locator = mesh.locator();
        scene.tf = {table.data(), 2, 0.f, 2.f};
        scene.bounds = mesh.tets.bounds;
        scene.params.step = step;
        scene.params.opacityUnit = unit;
        scene.params.terminationAlpha = 0.99f;
    }
};

/// Samples the global grid k * s puts inside [t0, t1].
int gridSamples(float t0, float t1, float s) {
    return static_cast<int>(std::floor(t1 / s) - std::ceil(t0 / s)) + 1;
}

TEST(ReferenceMarcher, ConstantMediumMatchesBeerLambert) {
    // Opacity 0.3 per unit 0.5: over length L the exact opacity is 1 - exp(-0.3 L / 0.5)
    // (attenuation) or 1 - 0.7^(L / 0.5) (transmittance); point samples and pre-integration.
    const float step = 0.01f, unit = 0.5f;
    for (const OpacityLaw law : {OpacityLaw::Attenuation, OpacityLaw::Transmittance})
        for (const bool preintegrated : {true, false}) {
            const std::string what =
                std::string(opacityLawName(law)) + (preintegrated ? " preintegrated" : " point");
            Fixture f(twoCubes(), Vec4f(1.f, 0.5f, 0.25f, 0.3f), step, unit);
            f.scene.tf.law = law;
            f.scene.params.terminationAlpha = 1.f;
            f.scene.params.preintegrated = preintegrated;
            // Ray along +x through both cubes (y, z inside): crosses 2 units of medium and the
            // gap.
            const Ray ray{{-0.5f, 0.37f, 0.61f}, {1.f, 0.f, 0.f}};
            RayCounters counters;
            const Vec4f c = marchReference(f.scene, ray, counters);
            const int inFirst = gridSamples(0.5f, 1.5f, step),
                      inSecond = gridSamples(2.5f, 3.5f, step);
            if (!preintegrated) {
                EXPECT_NEAR(c.w, testing::slabOpacity(0.3, (inFirst + inSecond) * step, unit, law),
                            1e-4f)
                    << what;
            }
            // The continuous answer.
            EXPECT_NEAR(c.w, testing::slabOpacity(0.3, 2.0, unit, law), 0.01f) << what;
            EXPECT_NEAR(c.x / c.w, 1.f, 1e-5f) << what;   // premultiplied colour over alpha is the
            EXPECT_NEAR(c.y / c.w, 0.5f, 1e-5f) << what;  // TF colour
            // The gap takes two samples: the first, found outside, asks where the ray enters
            // the mesh again (outsideUntil), and the ray goes on to the last grid point before.
            EXPECT_EQ(counters.samples, static_cast<std::uint32_t>(inFirst + 2 + inSecond)) << what;
        }
}

TEST(ReferenceMarcher, GapsAndMissesAreTransparent) {
    Fixture f(twoCubes(), Vec4f(1.f, 1.f, 1.f, 0.9f), 0.02f, 1.f);
    RayCounters counters;
    // Through the gap only (x = 1.5), along y.
    EXPECT_EQ(marchReference(f.scene, {{1.5f, -1.f, 0.5f}, {0.f, 1.f, 0.f}}, counters).w, 0.f);
    EXPECT_GT(counters.samples, 0u);  // inside the bounds, so samples are taken
    // Missing the bounds entirely takes no sample.
    RayCounters none;
    EXPECT_EQ(marchReference(f.scene, {{0.5f, 5.f, 0.5f}, {0.f, 1.f, 0.f}}, none).w, 0.f);
    EXPECT_EQ(none.samples, 0u);
}

TEST(ReferenceMarcher, EarlyTerminationStopsAtOpacity) {
    Fixture f(twoCubes(), Vec4f(1.f, 1.f, 1.f, 1.f), 0.01f, 1.f);
    // Opacity 1 under the transmittance law: a point sample is opaque at once; a pre-integrated
    // segment once the second sample closes it.
    f.scene.tf.law = OpacityLaw::Transmittance;
    for (const bool preintegrated : {false, true}) {
        f.scene.params.preintegrated = preintegrated;
        RayCounters counters;
        const Vec4f c = marchReference(f.scene, {{-0.5f, 0.4f, 0.4f}, {1.f, 0.f, 0.f}}, counters);
        EXPECT_FLOAT_EQ(c.w, 1.f);
        EXPECT_EQ(counters.samples, preintegrated ? 2u : 1u);
    }
    // Under attenuation opacity 1 is an extinction of 1 per unit: the two unit cubes leave
    // e^-2 of the light, the ray runs through both.
    f.scene.tf.law = OpacityLaw::Attenuation;
    f.scene.params.terminationAlpha = 1.f;
    for (const bool preintegrated : {false, true}) {
        f.scene.params.preintegrated = preintegrated;
        RayCounters counters;
        const Vec4f c = marchReference(f.scene, {{-0.5f, 0.4f, 0.4f}, {1.f, 0.f, 0.f}}, counters);
        EXPECT_NEAR(c.w, testing::slabOpacity(1.0, 2.0, 1.0), 0.01f);
        EXPECT_EQ(counters.samples, static_cast<std::uint32_t>(gridSamples(0.5f, 1.5f, 0.01f) + 2 +
                                                               gridSamples(2.5f, 3.5f, 0.01f)));
    }
}

TEST(ReferenceMarcher, NanValuesAreTransparent) {
    Mesh m = testing::makeHexGrid(2, 0.f, 1.f, [](Vec3f) { return NAN; });
    Fixture f(m, Vec4f(1.f, 1.f, 1.f, 0.5f), 0.05f, 1.f);
    RayCounters counters;
    EXPECT_EQ(marchReference(f.scene, {{-1.f, 0.5f, 0.5f}, {1.f, 0.f, 0.f}}, counters).w, 0.f);
}

TEST(ReferenceMarcher, CpuFrameMatchesPerRayMarching) {
    Mesh m = testing::makeHexGrid(
        4, -1.f, 1.f, [](Vec3f p) { return p.x + 2 * p.y - p.z; }, 0.2f);
    const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}));
    RenderSettings s;
    s.method = RenderMethod::Reference;
    s.width = 40;
    s.height = 30;
    s.tf.colors = {{0.f, {0, 0, 1}}, {1.f, {1, 0, 0}}};
    s.tf.opacities = {{0.f, 0.f}, {1.f, 0.8f}};
    const RenderResult r = renderCpu(pm, s);
    ASSERT_EQ(r.image.pixels.size(), 1200u);
    const SceneView scene = r.setup.scene(pm);
    std::uint64_t total = 0;
    for (int y = 0; y < s.height; ++y)
        for (int x = 0; x < s.width; ++x) {
            RayCounters counters;
            const Vec4f c = marchReference(scene, r.setup.rays.ray(x + 0.5f, y + 0.5f), counters);
            const Vec4f& p = r.image.at(x, y);
            ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.w));
            ASSERT_EQ(p.w, c.w);
            ASSERT_EQ(r.sampleCounts[y * s.width + x], counters.samples);
            total += counters.samples;
        }
    EXPECT_EQ(r.stats.samples, total);
    // The default camera fits the mesh: the centre is covered, the corners are empty.
    EXPECT_GT(r.image.at(20, 15).w, 0.1f);
    EXPECT_EQ(r.image.at(0, 0).w, 0.f);
}

}  // namespace
}  // namespace uvr

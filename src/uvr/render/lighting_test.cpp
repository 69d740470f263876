// SPDX-License-Identifier: MIT
// Gradient shading (issue 32): the headlight's light in every method and on every device.
// Oracles: a linear field (one gradient everywhere) lit in closed form, a constant field (no
// gradient: lit as facing the light), lighting that is the identity changing no bit, and the
// sampling methods converging to the exact integrator's lit image.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/lighting.h"

namespace uvr {
namespace {

float roundField(Vec3f p) {
    return 1.5f * length(p - Vec3f(0.45f, 0.5f, 0.55f));
}

/// A lighting with every term at work (smooth normals, or each cell's).
Lighting someLight(bool smooth = true) {
    Lighting l;
    l.on = true;
    l.smooth = smooth;
    l.ambient = 0.15f, l.diffuse = 0.6f, l.specular = 0.25f, l.specularPower = 6.f;
    return l;
}

TEST(LightFactors, HeadlightCosineInClosedForm) {
    const Lighting l = someLight();
    const Vec3f dir = normalize(Vec3f(0.3f, -0.4f, 0.8f));
    const Vec3f g(2.f, 1.f, -0.5f);
    const float c = std::fabs(dot(g, dir)) / length(g);
    const LightFactors f = lightFactors(l, g, dir);
    EXPECT_NEAR(f.scale, 0.15f + 0.6f * c, 1e-6f);
    EXPECT_NEAR(f.add, 0.25f * std::pow(c, 6.f), 1e-6f);
    // Two-sided: the gradient's sign does not matter.
    EXPECT_FLOAT_EQ(lightFactors(l, g * -1.f, dir).scale, f.scale);
    // No normal (zero, huge, NaN): lit as facing the light.
    for (const Vec3f bad : {Vec3f(0.f), Vec3f(NAN, 0.f, 1.f), Vec3f(INFINITY, 0.f, 0.f)}) {
        const LightFactors b = lightFactors(l, bad, dir);
        EXPECT_FLOAT_EQ(b.scale, 0.75f);
        EXPECT_FLOAT_EQ(b.add, 0.25f);
    }
    // Gradients at float's ends keep their direction.
    EXPECT_NEAR(lightFactors(l, g * 1e37f, dir).scale, f.scale, 1e-6f);
    EXPECT_NEAR(lightFactors(l, g * 1e-40f, dir).scale, f.scale, 1e-5f);
    // Off: the identity.
    Lighting off = l;
    off.on = false;
    EXPECT_TRUE(lightFactors(off, g, dir).identity());
}

class Lit : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Lit);

TEST_P(Lit, ALinearFieldIsLitInClosedForm) {
    // One gradient everywhere, rays along +x: every point gets scale = ambient + diffuse c and
    // add = specular c^power with c = |g.x| / |g|, so the lit pixel is the unlit one's colour
    // times scale plus its opacity times add, and the same opacity.
    // Smooth normals too: every point's mean of equal gradients is that gradient.
    const Vec3f g = testing::kLinearGradient;
    const float c = std::fabs(g.x) / length(g);
    for (const bool split : {true, false})
        for (const bool smooth : {false, true}) {
            const Lighting l = someLight(smooth);
            const float scale = l.ambient + l.diffuse * c,
                        add = l.specular * std::pow(c, l.specularPower);
            const PreparedMesh pm = testing::smoothGradientGrid(testing::linearField, split);
            for (const RenderMethod m : testing::kEveryMethod) {
                RenderSettings s = testing::viewAlongX(m);
                const RenderResult unlit = render(pm, s);
                s.lighting = l;
                const RenderResult lit = render(pm, s);
                const std::string what = std::string(methodName(m)) +
                                         (split ? " tetrahedra" : " hexahedra") +
                                         (smooth ? " smooth" : " cell");
                for (std::size_t i = 0; i < lit.image.pixels.size(); ++i) {
                    const Vec4f u = unlit.image.pixels[i], p = lit.image.pixels[i];
                    ASSERT_GT(u.w, 0.4f) << what;  // the ray crosses the cube
                    EXPECT_NEAR(p.w, u.w, 1e-6f) << what << " pixel " << i;
                    EXPECT_NEAR(p.x, u.x * scale + u.w * add, 2e-5f) << what << " pixel " << i;
                    EXPECT_NEAR(p.y, u.y * scale + u.w * add, 2e-5f) << what << " pixel " << i;
                    EXPECT_NEAR(p.z, u.z * scale + u.w * add, 2e-5f) << what << " pixel " << i;
                }
            }
        }
}

TEST_P(Lit, AConstantFieldIsLitAsFacingTheLight) {
    // No gradient, no normal: every point is lit as facing the light (ambient + diffuse,
    // specular), the same in every method.
    const Lighting l = someLight();
    const PreparedMesh pm = testing::smoothGradientGrid(testing::constantField, true);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = testing::viewAlongX(m);
        const RenderResult unlit = render(pm, s);
        s.lighting = l;
        const RenderResult lit = render(pm, s);
        const Vec4f u = unlit.image.at(12, 8), p = lit.image.at(12, 8);
        EXPECT_NEAR(p.x, u.x * 0.75f + u.w * 0.25f, 2e-5f) << methodName(m);
        EXPECT_NEAR(p.w, u.w, 1e-6f) << methodName(m);
    }
}

TEST_P(Lit, IdentityLightChangesNoBit) {
    // Lighting off whatever its coefficients, or on with ambient 1 and nothing else: the unlit
    // pixels bit for bit.
    const PreparedMesh pm = testing::smoothGradientGrid(roundField, false, 0.2f);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = testing::viewAlongX(m);
        const RenderResult unlit = render(pm, s);
        s.lighting = someLight();
        s.lighting.on = false;
        EXPECT_TRUE(testing::samePixels(render(pm, s).image, unlit.image)) << methodName(m);
        s.lighting = Lighting{};
        s.lighting.on = true, s.lighting.ambient = 1.f, s.lighting.diffuse = 0.f;
        EXPECT_TRUE(testing::samePixels(render(pm, s).image, unlit.image)) << methodName(m);
    }
}

TEST_P(Lit, SamplingConvergesToTheExactLight) {
    // A curved field, so the light turns from cell to cell: with short steps the sampling
    // methods' lit images approach the exact integrator's (each segment lit by the mean of its
    // samples' lights, against the light of every cell crossed), tetrahedra and hexahedra.
    // (Smooth normals turn smoothly, per-cell ones jump at every face: the smooth light comes
    // closer.)
    for (const bool smooth : {false, true})
        for (const bool split : {true, false}) {
            const PreparedMesh pm = testing::smoothGradientGrid(roundField, split, 0.2f);
            RenderSettings s = testing::viewAlongX(RenderMethod::Exact);
            s.lighting = someLight(smooth);
            const Image exact = render(pm, s).image;
            for (const RenderMethod m : {RenderMethod::Reference, RenderMethod::Partitions}) {
                s.method = m;
                s.step = 0.002f;
                const Image sampled = render(pm, s).image;
                float worst = 0.f;
                for (std::size_t i = 0; i < exact.pixels.size(); ++i)
                    for (int k = 0; k < 4; ++k)
                        worst =
                            std::fmax(worst, std::fabs(exact.pixels[i][k] - sampled.pixels[i][k]));
                EXPECT_LT(worst, smooth ? 0.004f : 0.01f)
                    << methodName(m) << (split ? " tetrahedra" : " hexahedra")
                    << (smooth ? " smooth" : " cell");
            }
        }
}

TEST_P(Lit, NanValuesAndDegenerateGradientsStayFinite) {
    // A field of NaN in part of the cube: the NaN cells have no gradient (lit as facing the
    // light) and no pixel turns NaN.
    const PreparedMesh pm = testing::smoothGradientGrid(
        [](Vec3f p) { return p.x > 0.5f && p.y > 0.4f ? NAN : roundField(p); }, true, 0.1f);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = testing::viewAlongX(m);
        s.tf.nanOpacity = 0.5f;
        s.lighting = someLight();
        for (const Vec4f& p : render(pm, s).image.pixels)
            for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(p[k])) << methodName(m);
    }
}

TEST(SmoothGradients, ALinearFieldGivesItsGradientAtEveryPoint) {
    // Tetrahedra and native hexahedra: every point's volume-weighted mean of equal gradients.
    const Vec3f want = testing::kLinearGradient;
    for (const bool split : {true, false}) {
        const PreparedMesh pm = testing::smoothGradientGrid(testing::linearField, split, 0.2f);
        ASSERT_TRUE(hasSmoothGradients(pm.tets));
        ASSERT_EQ(pm.tets.blockGradients.size(), pm.tets.blockVertices.size());
        for (const Vec3f& g : pm.tets.blockGradients)
            ASSERT_LT(length(g - want), 1e-4f) << (split ? "tetrahedra" : "hexahedra");
        EXPECT_EQ(pm.tets.pointGradients.empty(), split);  // per point only for native cells
        for (const Vec3f& g : pm.tets.pointGradients) ASSERT_LT(length(g - want), 1e-4f);
        // Interpolated anywhere in a cell: the same gradient.
        const TetMeshView v = pm.kernelMesh();
        const float bary[4] = {0.1f, 0.2f, 0.3f, 0.4f};
        EXPECT_LT(length(v.gradient(0, bary, true) - want), 1e-4f);
        EXPECT_LT(length(v.gradient(v.cellCount() - 1, bary, true) - want), 1e-4f);
    }
}

TEST(SmoothGradients, CurvedFieldsTurnAndUnmadeOnesFallBackToTheCells) {
    // On the distance to a point, smooth gradients point away from it; a mesh whose smooth
    // gradients were not made falls back to each cell's gradient.
    const Mesh m = testing::makeHexGrid(6, 0.f, 1.f, roundField);
    PrepareOptions options;
    options.cells.splitCells = true;
    PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), options);
    const float centre[4] = {0.25f, 0.25f, 0.25f, 0.25f};
    EXPECT_FALSE(hasSmoothGradients(pm.tets));
    const Vec3f perCell = pm.kernelMesh().gradient(0, centre, false);
    EXPECT_EQ(pm.kernelMesh().gradient(0, centre, true), perCell);
    computeSmoothGradients(pm.tets);
    const Vec3f smooth = pm.kernelMesh().gradient(0, centre, true);
    EXPECT_NE(smooth, perCell);
    // Cell 0 lies near the origin, away from the centre (0.45, 0.5, 0.55): the gradient points
    // from the centre to it.
    EXPECT_LT(smooth.x, 0.f);
    EXPECT_LT(smooth.y, 0.f);
    EXPECT_LT(smooth.z, 0.f);
}

}  // namespace
}  // namespace uvr

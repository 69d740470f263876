// SPDX-License-Identifier: MIT
// Gradient opacity (issue 32; VTK's vtkVolumeProperty::SetGradientOpacity): the transfer
// function's opacity scaled by a piecewise linear function of the field gradient's magnitude,
// in every method and on every device. Oracles: over a linear field (one gradient everywhere)
// a scale s is the opacity unit divided by s, in closed form for the extinction; a scale of 0
// hides a region and 1 changes no bit; the sampling methods converge to the exact integrator
// where the magnitude varies; the magnitudes are the file's on a mesh rendered scaled.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/lighting.h"
#include "uvr/render/render_settings.h"

namespace uvr {
namespace {

/// A field whose gradient's magnitude runs from 0 to 2 sqrt(3) across the cube.
float bowlField(Vec3f p) {
    return dot(p, p) * 0.4f;
}

TEST(GradientOpacity, PiecewiseLinearAndConstantBeyondItsEnds) {
    const GradientOpacity g = parseGradientOpacity("0.5:0,1.5:1,3:0.25");
    ASSERT_EQ(g.count, 3);
    EXPECT_FLOAT_EQ(g.at(0.f), 0.f);
    EXPECT_FLOAT_EQ(g.at(0.5f), 0.f);
    EXPECT_FLOAT_EQ(g.at(1.f), 0.5f);
    EXPECT_FLOAT_EQ(g.at(1.5f), 1.f);
    EXPECT_FLOAT_EQ(g.at(2.25f), 0.625f);
    EXPECT_FLOAT_EQ(g.at(100.f), 0.25f);
    EXPECT_FLOAT_EQ(g.at(INFINITY), 0.25f);
    EXPECT_FLOAT_EQ(g.at(NAN), 0.f);  // no gradient: the first point's
    // A step (two points at one magnitude) and a single point (a constant).
    const GradientOpacity step = parseGradientOpacity("1:0,1:1");
    EXPECT_FLOAT_EQ(step.at(0.999f), 0.f);
    EXPECT_FLOAT_EQ(step.at(1.001f), 1.f);
    EXPECT_FLOAT_EQ(parseGradientOpacity("7:0.3").at(0.f), 0.3f);
    // The text round-trips in shortest decimals.
    EXPECT_EQ(gradientOpacityText(g), "0.5:0,1.5:1,3:0.25");
    EXPECT_EQ(gradientOpacityText(parseGradientOpacity("0.1:1")), "0.1:1");
    EXPECT_EQ(gradientOpacityText(GradientOpacity{}), "");
    // The magnitude of a gradient at float's ends, and none for a non-finite one.
    EXPECT_FLOAT_EQ(gradientMagnitude(Vec3f(3.f, 4.f, 0.f)), 5.f);
    EXPECT_FLOAT_EQ(gradientMagnitude(Vec3f(3e37f, 4e37f, 0.f)), 5e37f);
    EXPECT_NEAR(gradientMagnitude(Vec3f(3e-40f, 4e-40f, 0.f)), 5e-40f, 1e-44f);
    EXPECT_FLOAT_EQ(gradientMagnitude(Vec3f(0.f)), 0.f);
    EXPECT_TRUE(std::isnan(gradientMagnitude(Vec3f(NAN, 0.f, 1.f))));
    EXPECT_TRUE(std::isnan(gradientMagnitude(Vec3f(INFINITY, 0.f, 1.f))));
    // The light's factors carry it, shaded or not; off, the opacity is 1.
    const Lighting l;
    EXPECT_TRUE(readsGradient(l, g));
    EXPECT_FALSE(readsGradient(l, GradientOpacity{}));
    EXPECT_FLOAT_EQ(lightFactors(l, g, Vec3f(1.f, 0.f, 0.f), Vec3f(0.f, 0.f, 1.f)).opacity, 0.5f);
    EXPECT_TRUE(lightFactors(l, g, Vec3f(1.f, 0.f, 0.f), Vec3f(0.f, 0.f, 1.f)).identity());
    EXPECT_FLOAT_EQ(
        lightFactors(l, GradientOpacity{}, Vec3f(1.f, 0.f, 0.f), Vec3f(0.f, 0.f, 1.f)).opacity,
        1.f);
}

TEST(GradientOpacity, BadTextsAreRefusedNamingTheSetting) {
    for (const char* bad :
         {"", "1", "1:", ":1", "a:1", "1:b", "1:0.5,", "-1:0.5", "1:1.5", "1:-0.1", "2:1,1:0",
          "inf:1", "1:nan", " 1:1", "1;1", "0:0,1:0,2:0,3:0,4:0,5:0,6:0,7:0,8:0"}) {
        try {
            parseGradientOpacity(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const SettingError& e) {
            EXPECT_EQ(e.setting(), "gradient_opacity") << bad;
            EXPECT_EQ(e.value(), bad);
            EXPECT_NE(e.expected().find("MAGNITUDE:SCALE"), std::string::npos) << e.expected();
        }
    }
    // Eight points are the most.
    EXPECT_EQ(parseGradientOpacity("0:0,1:0,2:0,3:0,4:0,5:0,6:0,7:1").count, 8);
    // The settings' check refuses one built by hand.
    RenderSettings s;
    s.tf = transferFunctionPreset("viridis");
    validateSettings(s);
    s.gradientOpacity = parseGradientOpacity("1:0,2:1");
    validateSettings(s);
    s.gradientOpacity.scale[1] = 2.f;
    EXPECT_THROW(validateSettings(s), SettingError);
    s.gradientOpacity.scale[1] = 1.f;
    s.gradientOpacity.magnitude[0] = NAN;
    EXPECT_THROW(validateSettings(s), SettingError);
}

class GradientOpacityOn : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(GradientOpacityOn);

TEST_P(GradientOpacityOn, OverALinearFieldAScaleDividesTheOpacityUnit) {
    // One gradient everywhere: the scale s the function gives its magnitude multiplies the
    // extinction everywhere, which is the image of opacity unit u / s, in every method, over
    // tetrahedra and native hexahedra, with each cell's gradient and the smooth ones, shaded
    // or not.
    const float m = length(testing::kLinearGradient);
    for (const bool split : {true, false}) {
        const PreparedMesh pm = testing::smoothGradientGrid(testing::linearField, split);
        for (const bool smooth : {false, true})
            for (const bool shaded : {false, true})
                for (const RenderMethod method : testing::kEveryMethod) {
                    const std::string what =
                        std::string(methodName(method)) + (split ? " tetrahedra" : " hexahedra") +
                        (smooth ? " smooth" : " cell") + (shaded ? " shaded" : "");
                    RenderSettings s = testing::viewAlongX(method);
                    s.lighting.on = shaded;
                    s.lighting.smooth = smooth;
                    s.lighting.diffuse = 0.7f, s.lighting.ambient = 0.2f;
                    s.maxStep = 0.03f;  // the adaptive steps a gradient opacity takes
                    RenderSettings scaled = s;
                    scaled.opacityUnit = 1.f / 0.4f;
                    const RenderResult want = render(pm, scaled);
                    // 0.4 at the gradient's magnitude (between the points at 0 and 2 m).
                    s.gradientOpacity =
                        parseGradientOpacity("0:0.1," + std::to_string(2.f * m) + ":0.7");
                    const RenderResult got = render(pm, s);
                    ASSERT_GT(want.image.at(12, 8).w, 0.1f) << what;
                    EXPECT_LT(testing::maxPixelDifference(got.image, want.image), 2e-5f) << what;
                }
    }
}

TEST_P(GradientOpacityOn, ZeroHidesFlatRegionsAndOneChangesNoBit) {
    // A constant field has no gradient: a function at 0 there hides it. A linear field steeper
    // than the function's last point: scale 1, the image without the function bit for bit.
    for (const bool split : {true, false}) {
        const PreparedMesh flat = testing::smoothGradientGrid(testing::constantField, split);
        const PreparedMesh steep = testing::smoothGradientGrid(testing::linearField, split);
        for (const RenderMethod method : testing::kEveryMethod) {
            const std::string what =
                std::string(methodName(method)) + (split ? " tetrahedra" : " hexahedra");
            RenderSettings s = testing::viewAlongX(method);
            s.maxStep = 0.03f;  // the adaptive steps a gradient opacity takes by default
            const RenderResult plain = render(steep, s);
            ASSERT_GT(render(flat, s).image.at(12, 8).w, 0.1f) << what;
            s.gradientOpacity = parseGradientOpacity("0:0,0.1:1");
            for (const Vec4f& p : render(flat, s).image.pixels) ASSERT_EQ(p.w, 0.f) << what;
            EXPECT_TRUE(testing::samePixels(render(steep, s).image, plain.image)) << what;
        }
    }
}

TEST_P(GradientOpacityOn, SamplingConvergesToTheExactIntegrator) {
    // The magnitude varies from cell to cell: with short steps the sampling methods' images
    // approach the exact integrator's (each segment scaled by the mean of its samples' scales,
    // against each cell's own), tetrahedra and hexahedra, each cell's gradients and the smooth
    // ones.
    for (const bool smooth : {false, true})
        for (const bool split : {true, false}) {
            const PreparedMesh pm = testing::smoothGradientGrid(bowlField, split, 0.2f);
            RenderSettings s = testing::viewAlongX(RenderMethod::Exact);
            applyOpacitySpec(s.tf, "constant:0.9");
            s.lighting.smooth = smooth;
            s.gradientOpacity = parseGradientOpacity("0:0,1:0.2,2:1");
            const Image exact = render(pm, s).image;
            s.gradientOpacity = GradientOpacity{};
            const Image without = render(pm, s).image;
            s.gradientOpacity = parseGradientOpacity("0:0,1:0.2,2:1");
            // The function changes the picture well beyond the methods' differences.
            EXPECT_GT(testing::maxPixelDifference(exact, without), 0.1f);
            for (const RenderMethod m : {RenderMethod::Reference, RenderMethod::Partitions}) {
                s.method = m;
                s.step = 0.002f;
                s.maxStep = 0.004f;
                EXPECT_LT(testing::maxPixelDifference(exact, render(pm, s).image),
                          smooth ? 0.004f : 0.01f)
                    << methodName(m) << (split ? " tetrahedra" : " hexahedra")
                    << (smooth ? " smooth" : " cell");
            }
        }
}

TEST_P(GradientOpacityOn, MagnitudesAreTheFilesOnAMeshRenderedScaled) {
    // A mesh 1e-9 across renders scaled to a diagonal of about 1 (MeshFrame): its gradients
    // there are 1e-9 of the file's, and the function's magnitudes, given in the file's units,
    // still pick the scale of the file's gradient.
    const float size = 1e-9f, valueScale = 1e-9f;  // gradient in the file: kLinearGradient
    const PreparedMesh pm =
        testing::smoothGradientGrid(testing::linearField, true, 0.f, size, valueScale);
    ASSERT_FALSE(pm.tets.frame.identity());
    const float m = length(testing::kLinearGradient);
    for (const RenderMethod method : testing::kEveryMethod) {
        RenderSettings s = testing::viewAlongX(method, size);
        s.range = {-0.5e-9f, 1.2e-9f};
        RenderSettings scaled = s;
        scaled.opacityUnit = size / 0.5f;
        const RenderResult want = render(pm, scaled);
        s.gradientOpacity = parseGradientOpacity("0:0," + std::to_string(2.f * m) + ":1");
        const RenderResult got = render(pm, s);
        ASSERT_GT(want.image.at(12, 8).w, 0.1f) << methodName(method);
        EXPECT_LT(testing::maxPixelDifference(got.image, want.image), 2e-5f) << methodName(method);
    }
}

TEST_P(GradientOpacityOn, CellDataIsRefusedNamingTheField) {
    Mesh m = testing::makeHexGrid(3, 0.f, 1.f, testing::linearField);
    Field cells{"c", Association::Cell, 1, std::vector<float>(27, 1.f)};
    m.fields.push_back(cells);
    const PreparedMesh pm =
        prepareMesh(m, selectScalarField(m, parseFieldSpec("c")), PrepareOptions{});
    RenderSettings s = testing::viewAlongX(RenderMethod::Exact);
    s.gradientOpacity = parseGradientOpacity("0:0,1:1");
    try {
        render(pm, s);
        ADD_FAILURE() << "rendered a gradient opacity on cell data";
    } catch (const SettingError& e) {
        EXPECT_EQ(e.setting(), "gradient_opacity");
        EXPECT_NE(std::string(e.what()).find("cell data"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace uvr

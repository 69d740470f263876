// SPDX-License-Identifier: MIT
// Isosurfaces inside the volume (issue 32) in every method and on every device. Oracles: the
// distance to a centre, whose isosurface is a sphere of the value's radius (its interpolation
// is convex, so the surface lies inside the sphere and within the interpolation's error of
// it); a linear field, whose isosurface is a plane, composited over the volume behind it as the
// volume clipped at that plane plus the lit surface; translucent surfaces in depth order in
// closed form; values the field never takes changing no bit.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/smooth_gradients.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/isosurface.h"

namespace uvr {
namespace {

const Vec3f kCentre(0.5f, 0.5f, 0.5f);
float distanceField(Vec3f p) {
    return length(p - kCentre);
}
/// An n^3 grid of hexahedra over [0, 1]^3 with the field f, as native cells or split into
/// tetrahedra, with its smooth gradients.
PreparedMesh smoothGrid(float (*f)(Vec3f), bool split, int n = 16) {
    const Mesh m = testing::makeHexGrid(n, 0.f, 1.f, f);
    PrepareOptions options;
    options.kd.leafCells = 64;  // several partitions along each ray
    options.cells.splitCells = split;
    PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), options);
    computeSmoothGradients(pm.tets);
    return pm;
}

/// A parallel view along +x through the cube's middle, `size` pixels square over 0.8 x 0.8,
/// transparent volume (the surfaces alone) unless the caller sets an opacity.
RenderSettings surfacesAlongX(RenderMethod method, int size = 48) {
    RenderSettings s;
    s.method = method;
    s.width = s.height = size;
    Camera c;
    c.position = Vec3f(-2.f, 0.5f, 0.5f);
    c.focalPoint = kCentre;
    c.viewUp = Vec3f(0.f, 0.f, 1.f);
    c.parallelProjection = true;
    c.parallelScale = 0.4f;
    s.camera = c;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "constant:0");
    s.range = {0.f, 1.f};
    s.opacityUnit = 1.f;
    s.opacityLaw = OpacityLaw::Attenuation;
    return s;
}

/// An opaque white isosurface at v.
IsoSurface white(float v, float opacity = 1.f) {
    IsoSurface iso;
    iso.value = v;
    iso.opacity = opacity;
    iso.colorMapped = false;
    iso.color = Vec3f(1.f, 1.f, 1.f);
    return iso;
}

/// Distance from the sphere's centre to the ray of pixel (x, y).
float rayDistance(const RenderResult& r, int x, int y) {
    const Ray ray = r.setup.rays.ray(float(x) + 0.5f, float(y) + 0.5f);
    const Vec3f oc = kCentre - ray.org;
    return length(oc - ray.dir * dot(oc, ray.dir));
}

class Iso : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Iso);

TEST_P(Iso, TheDistanceToACentreGivesASphereOfTheValuesRadius) {
    // Interpolated linearly (tetrahedra) or trilinearly (hexahedra), the distance is convex, so
    // its interpolation lies above it: the surface lies inside the sphere (no ray passing
    // outside it is hit), and within the interpolation's error of it (on this 16^3 grid at
    // most h^2 / (2 r) = 0.007 for a tetrahedron's longest edge h = sqrt(3) / 16). The
    // silhouette's area gives the radius to within a third of a pixel (1/60).
    const float r = 0.3f, tol = 0.01f, pixel = 0.8f / 48.f;
    for (const bool split : {true, false}) {
        const PreparedMesh pm = smoothGrid(distanceField, split);
        for (const RenderMethod m : testing::kEveryMethod) {
            RenderSettings s = surfacesAlongX(m);
            s.isoSurfaces = {white(r)};
            const RenderResult res = render(pm, s);
            const std::string what =
                std::string(methodName(m)) + (split ? " tetrahedra" : " hexahedra");
            int covered = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const float d = rayDistance(res, x, y), a = res.image.at(x, y).w;
                    if (d > r) {
                        EXPECT_EQ(a, 0.f) << what << " at " << x << "," << y;
                    }
                    if (d < r - tol) {
                        EXPECT_EQ(a, 1.f) << what << " at " << x << "," << y;
                    }
                    covered += a > 0.5f;
                }
            const float measured = std::sqrt(float(covered) / float(M_PI)) * pixel;
            EXPECT_NEAR(measured, r, pixel / 3.f) << what;
        }
    }
}

TEST_P(Iso, APlaneIsCompositedOverTheVolumeInFrontOfIt) {
    // A linear field's isosurface is the plane g . p = c. Rays along +x meet the volume in
    // front of it (the volume clipped there, rendered on its own) and then the opaque surface
    // of the colour map's colour at c, lit by the headlight: scale ambient + diffuse cos with
    // cos = |g.x| / |g| (specular 0.3 adds 0.3 cos^8).
    const float c = 0.45f;
    const Vec3f g = testing::kLinearGradient;
    const float cosine = std::fabs(g.x) / length(g);
    for (const bool split : {true, false}) {
        const PreparedMesh pm = smoothGrid(testing::linearField, split, 6);
        for (const RenderMethod m : testing::kEveryMethod) {
            RenderSettings s = surfacesAlongX(m, 24);
            applyOpacitySpec(s.tf, "constant:0.6");
            s.range = {-0.5f, 1.2f};
            s.step = 0.01f;
            s.lighting.specular = 0.3f, s.lighting.specularPower = 8.f;
            RenderSettings front = s;
            const Vec3f n = g * -1.f;  // keeps g . p <= c
            front.clipPlanes = {{g * (c / dot(g, g)), n}};
            const RenderResult before = render(pm, front);
            s.isoSurfaces = {IsoSurface{c}};
            const RenderResult res = render(pm, s);
            const Vec3f colour = res.setup.tfView().sample(c).xyz();
            const float scale = cosine, add = 0.3f * std::pow(cosine, 8.f);
            const float tol = m == RenderMethod::Exact ? 2e-4f : 6e-3f;
            const std::string what =
                std::string(methodName(m)) + (split ? " tetrahedra" : " hexahedra");
            int hits = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    // Only rays that meet the plane inside the cube.
                    const Ray ray = res.setup.rays.ray(float(x) + 0.5f, float(y) + 0.5f);
                    const float t = (c - dot(g, ray.org)) / dot(g, ray.dir);
                    const Vec3f p = ray.at(t);
                    if (!(p.x > 0.02f && p.x < 0.98f && p.y > 0.02f && p.y < 0.98f && p.z > 0.02f &&
                          p.z < 0.98f))
                        continue;
                    ++hits;
                    const Vec4f f = before.image.at(x, y), got = res.image.at(x, y);
                    const float rest = 1.f - f.w;
                    EXPECT_NEAR(got.w, 1.f, 1e-6f) << what;
                    EXPECT_NEAR(got.x, f.x + rest * (colour.x * scale + add), tol) << what;
                    EXPECT_NEAR(got.y, f.y + rest * (colour.y * scale + add), tol) << what;
                    EXPECT_NEAR(got.z, f.z + rest * (colour.z * scale + add), tol) << what;
                }
            EXPECT_GT(hits, 100) << what;
        }
    }
}

TEST_P(Iso, TranslucentSurfacesCompositeInDepthOrder) {
    // Rays along +x through a field that grows with x meet the value 0.2 before 0.5, whichever
    // order they are given in: red at opacity 0.5 over blue at 0.5 gives (0.5 s, 0, 0.25 s,
    // 0.75) premultiplied, s the diffuse light cos.
    const Vec3f g = testing::kLinearGradient;
    const float cosine = std::fabs(g.x) / length(g);
    const PreparedMesh pm = smoothGrid(testing::linearField, true, 6);
    IsoSurface red = white(0.2f, 0.5f), blue = white(0.5f, 0.5f);
    red.color = Vec3f(1.f, 0.f, 0.f);
    blue.color = Vec3f(0.f, 0.f, 1.f);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = surfacesAlongX(m, 24);
        s.isoSurfaces = {blue, red};
        const RenderResult res = render(pm, s);
        // The middle ray meets both inside the cube (x = 0.04 and 0.54 on the ray z = y = 0.5).
        const Vec4f p = res.image.at(12, 12);
        EXPECT_NEAR(p.x, 0.5f * cosine, 1e-5f) << methodName(m);
        EXPECT_NEAR(p.y, 0.f, 1e-6f) << methodName(m);
        EXPECT_NEAR(p.z, 0.25f * cosine, 1e-5f) << methodName(m);
        EXPECT_NEAR(p.w, 0.75f, 1e-6f) << methodName(m);
    }
}

float xField(Vec3f p) {
    return p.x;
}

TEST_P(Iso, SurfacesBetweenTheBoundaryAndTheNearestSampleAreFound) {
    // The field x over [0, 1]^3, rays along +x from x = -2, steps of 0.07: the grid's samples
    // inside lie at x = 0.03 ... 0.94, so surfaces at 0.015 and 0.97 lie between the mesh's
    // boundary and the nearest sample, which no pair of samples brackets (sampleAtBoundary).
    // Every ray meets each. Also where the span ends at a clip plane (x <= 0.5 kept: samples up
    // to 0.45, the surface at 0.48).
    for (const bool split : {true, false}) {
        const PreparedMesh pm = smoothGrid(xField, split, 8);
        for (const RenderMethod m : testing::kEveryMethod)
            for (const float v : {0.015f, 0.97f, 0.48f}) {
                RenderSettings s = surfacesAlongX(m, 16);
                s.step = 0.07f;
                s.isoSurfaces = {white(v)};
                if (v == 0.48f) s.clipPlanes = {{Vec3f(0.5f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)}};
                const RenderResult res = render(pm, s);
                int hit = 0;
                for (int y = 0; y < s.height; ++y)
                    for (int x = 0; x < s.width; ++x) hit += res.image.at(x, y).w == 1.f;
                EXPECT_EQ(hit, s.width * s.height)
                    << methodName(m) << (split ? " tetrahedra" : " hexahedra") << " at " << v;
            }
    }
}

TEST_P(Iso, ValuesTheFieldNeverTakesChangeNoBit) {
    // An isosurface outside the field's range runs the lit integrators, which must give the
    // volume's pixels bit for bit (the samples gain only the probes for the mesh's boundary,
    // sampleAtBoundary); and the volume is still skipped where it is transparent.
    const PreparedMesh pm = smoothGrid(distanceField, true, 8);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = surfacesAlongX(m, 24);
        applyOpacitySpec(s.tf, "0:0,0.3:0,0.5:0.8,1:0.2");
        const RenderResult plain = render(pm, s);
        s.isoSurfaces = {white(5.f), white(-1.f, 0.3f)};
        const RenderResult with = render(pm, s);
        EXPECT_TRUE(testing::samePixels(with.image, plain.image)) << methodName(m);
        if (m == RenderMethod::Exact)
            EXPECT_EQ(with.stats.samples, plain.stats.samples);
        else  // at most eleven probes at each end of a run
            EXPECT_LE(with.stats.samples,
                      plain.stats.samples + 2 * 11 * std::uint64_t(s.width * s.height))
                << methodName(m);
        EXPECT_EQ(with.stats.partitionsSkipped, plain.stats.partitionsSkipped) << methodName(m);
    }
}

TEST_P(Iso, AnUnshadedFrameLightsItsSurfacesAsTheLitInstanceDoes) {
    // An unshaded frame with isosurfaces runs the instance without the volume's lighting code
    // (dispatchKernel); a gradient opacity of 1 everywhere changes no pixel but runs the lit
    // one. Both must light the surfaces with the frame's coefficients (and a translucent one
    // over a visible volume, on tetrahedra and hexahedra, smooth normals and per cell).
    for (const bool split : {true, false}) {
        const PreparedMesh pm = smoothGrid(distanceField, split, 8);
        for (const bool smooth : {true, false})
            for (const RenderMethod m : testing::kEveryMethod) {
                RenderSettings s = surfacesAlongX(m, 24);
                applyOpacitySpec(s.tf, "0:0,0.3:0,0.5:0.8,1:0.2");
                s.step = 1.f / 64.f;
                s.maxStep = 4.f * s.step;  // given: the opacity rule of lit frames stays off
                s.lighting.smooth = smooth;
                s.lighting.ambient = 0.2f;
                s.lighting.diffuse = 0.6f;
                s.lighting.specular = 0.4f;
                s.lighting.specularPower = 8.f;
                s.isoSurfaces = {white(0.25f, 0.5f), white(0.4f)};
                const RenderResult unlit = render(pm, s);
                s.gradientOpacity = parseGradientOpacity("0:1");
                const RenderResult lit = render(pm, s);
                const std::string what = std::string(methodName(m)) +
                                         (split ? " tetrahedra" : " hexahedra") +
                                         (smooth ? " smooth" : " per cell");
                EXPECT_LE(testing::maxPixelDifference(unlit.image, lit.image), 1e-6f) << what;
                EXPECT_EQ(unlit.stats.samples, lit.stats.samples) << what;
            }
    }
}

TEST_P(Iso, RaysThatCannotMeetASurfaceGiveTheSurfacesInstancesPixels) {
    // A frame with isosurfaces marches the rays that cross no partition holding an iso value
    // without the surfaces' code (isoRaySplit); the same frame with depth out marches every ray
    // with it. Their samples agree, and their pixels to rounding (the two instances' lighting
    // code is compiled apart: a shaded pixel may differ in its last bit). Opaque and translucent
    // surfaces over a visible volume, tetrahedra and hexahedra, pre-integrated or point
    // samples, shaded or not, clipped or not, the partitions skipped or not. And the frames do
    // split: some rays can meet a surface, some cannot.
    for (const bool split : {true, false}) {
        const PreparedMesh pm = smoothGrid(distanceField, split, 12);
        for (int variant = 0; variant < 5; ++variant) {
            RenderSettings s = surfacesAlongX(RenderMethod::Partitions, 32);
            applyOpacitySpec(s.tf, "0:0,0.3:0,0.5:0.8,1:0.2");
            s.isoSurfaces = {white(0.2f), white(0.3f, 0.4f)};
            s.preintegrated = variant != 1;
            s.lighting.on = variant == 2;
            if (variant == 3) s.clipPlanes = {{Vec3f(0.45f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
            s.skip = variant != 4;
            const std::string what = std::string(split ? "tetrahedra" : "hexahedra") +
                                     ", variant " + std::to_string(variant);
            const RenderResult splitFrame = render(pm, s);
            s.depthAlpha = 0.5f;
            const RenderResult whole = render(pm, s);
            EXPECT_LE(testing::maxPixelDifference(splitFrame.image, whole.image), 1e-6f) << what;
            EXPECT_EQ(splitFrame.sampleCounts, whole.sampleCounts) << what;
            PartitionSceneView scene;  // what the walk reads (a GPU frame keeps no shading here)
            scene.base = splitFrame.setup.scene(pm);
            scene.kd = pm.kd->view();
            int meets = 0;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x)
                    meets += mayMeetIsosurface(
                        scene, splitFrame.setup.rays.ray(float(x) + 0.5f, float(y) + 0.5f));
            EXPECT_GT(meets, 0) << what;
            EXPECT_LT(meets, s.width * s.height) << what;
        }
    }
}

TEST_P(Iso, PointSamplingFindsTheSurfaceBetweenSamples) {
    // Point samples: the surface between two samples at the linear reading's crossing.
    const PreparedMesh pm = smoothGrid(distanceField, true);
    for (const RenderMethod m : {RenderMethod::Reference, RenderMethod::Partitions}) {
        RenderSettings s = surfacesAlongX(m);
        s.preintegrated = false;
        s.isoSurfaces = {white(0.3f)};
        const RenderResult res = render(pm, s);
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const float d = rayDistance(res, x, y), a = res.image.at(x, y).w;
                if (d > 0.3f) {
                    EXPECT_EQ(a, 0.f) << methodName(m);
                }
                if (d < 0.29f) {
                    EXPECT_EQ(a, 1.f) << methodName(m);
                }
            }
    }
}

TEST_P(Iso, NanValuesStayFinite) {
    // NaN in part of the field: no surface where an end is NaN, no NaN pixel.
    const PreparedMesh pm = smoothGrid(
        [](Vec3f p) { return p.x > 0.5f && p.y > 0.4f ? NAN : distanceField(p); }, true, 8);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = surfacesAlongX(m, 24);
        s.tf.nanOpacity = 0.5f;
        s.isoSurfaces = {white(0.3f, 0.7f)};
        for (const Vec4f& p : render(pm, s).image.pixels)
            for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(p[k])) << methodName(m);
    }
}

TEST(IsoSettings, TextFormsReadBackAndBadOnesAreNamed) {
    for (const std::string text : {"0.5", "-3", "0.25,0.5", "1e+20,1,#ff8000"})
        EXPECT_EQ(isoText(parseIsoSurface(text)), text);
    const IsoSurface c = parseIsoSurface("2,0.4,#FF8000");
    EXPECT_FALSE(c.colorMapped);
    EXPECT_FLOAT_EQ(c.color.y, 128.f / 255.f);
    EXPECT_FLOAT_EQ(c.opacity, 0.4f);
    for (const std::string bad : {"", "x", "0.5,0", "0.5,1.5", "nan", "inf", "1,1,ff8000",
                                  "1,1,#ff80", "1,1,#gg0000", "1,2,3,4", " 1", "1,"}) {
        try {
            parseIsoSurface(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const SettingError& e) {
            EXPECT_EQ(e.setting(), "iso");
            EXPECT_NE(std::string(e.what()).find("VALUE[,OPACITY[,#RRGGBB]]"), std::string::npos)
                << e.what();
        }
    }
    RenderSettings s;
    s.isoSurfaces.assign(kMaxIsoSurfaces + 1, IsoSurface{});
    EXPECT_THROW(checkIso(s), SettingError);
    s.isoSurfaces = {white(0.5f)};
    s.isoSurfaces[0].color.x = 1.5f;
    EXPECT_THROW(checkIso(s), SettingError);
}

TEST(IsoSettings, CellDataHasNoIsosurfaces) {
    Mesh m = testing::makeHexGrid(4, 0.f, 1.f, distanceField);
    m.fields.push_back({"cells", Association::Cell, 1, std::vector<float>(m.cellCount(), 1.f)});
    PreparedMesh pm = prepareMesh(m, selectScalarField(m, parseFieldSpec("cells")), {});
    RenderSettings s = surfacesAlongX(RenderMethod::Exact, 8);
    s.isoSurfaces = {white(0.5f)};
    const std::string what = testing::catchError([&] { makeFrameSetup(pm, s); }).what();
    EXPECT_NE(what.find("isosurfaces need a point field"), std::string::npos) << what;
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// Clipping (issue 32): planes and a box cut every ray where they lie, in every method and on
// every device. Oracles: the closed form of a constant slab cut by a plane, a box around the mesh
// that changes nothing, and the two halves of a cut that composite to the whole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

PreparedMesh prepared(const Mesh& m) {
    PrepareOptions options;
    options.kd.leafCells = 32;  // several partitions along each ray
    return prepareMesh(m, selectScalarField(m, {}), options);
}

/// A 6^3 grid of hexahedra over [0, 1]^3 with a constant field.
PreparedMesh constantCube() {
    return prepared(testing::makeHexGrid(6, 0.f, 1.f));
}

/// A jittered 8^3 grid of hexahedra over [0, 1]^3 with a smooth field.
PreparedMesh wavyCube() {
    return prepared(testing::makeHexGrid(
        8, 0.f, 1.f, [](Vec3f p) { return std::sin(4.f * p.x) + p.y * p.z; }, 0.2f));
}

/// A frame looking along +x at the unit cube: a parallel view of its middle (every ray crosses
/// x from 0 to 1 inside the cube), or a perspective one from x = -2; constant opacity `opacity`
/// per unit length (attenuation), step 0.01.
RenderSettings clipViewAlongX(RenderMethod method, bool parallel,
                              const char* opacity = "constant:0.5") {
    RenderSettings s;
    s.method = method;
    s.width = 24, s.height = 16;
    Camera c;
    c.position = Vec3f(-2.f, 0.52f, 0.47f);
    c.focalPoint = Vec3f(0.5f, 0.52f, 0.47f);
    c.viewUp = Vec3f(0.f, 0.f, 1.f);
    c.viewAngle = 12.f;
    c.parallelProjection = parallel;
    c.parallelScale = 0.2f;
    s.camera = c;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, opacity);
    s.range = {-1.f, 2.f};
    s.opacityUnit = 1.f;
    s.opacityLaw = OpacityLaw::Attenuation;
    s.step = 0.01f;
    return s;
}

class Clipping : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Clipping);

TEST_P(Clipping, APlaneCutsTheSlabWhereItLies) {
    // Opacity 0.5 per unit along a chord of length L: alpha 1 - exp(-0.5 L). Kept x >= 0.37
    // leaves 0.63 of the unit chord, kept x <= 0.37 leaves 0.37. The exact method cuts at the
    // plane; the sampling methods take their samples inside it (within a step s1 = 0.01).
    const PreparedMesh pm = constantCube();
    for (const RenderMethod m : testing::kEveryMethod)
        for (const float side : {1.f, -1.f}) {
            RenderSettings s = clipViewAlongX(m, true);
            s.clipPlanes = {{Vec3f(0.37f, 0.f, 0.f), Vec3f(side * 3.f, 0.f, 0.f)}};  // not unit
            const double length = side > 0.f ? 0.63 : 0.37;
            const double want = -std::expm1(-0.5 * length);
            // A step of s1 = 0.01 more or less: 0.005 of optical depth.
            const float tol = m == RenderMethod::Exact ? 1e-4f : 6e-3f;
            const RenderResult r = render(pm, s);
            const std::string what = std::string(methodName(m)) + (side > 0 ? " x>=c" : " x<=c");
            for (const int y : {0, 8, 15})
                for (const int x : {0, 12, 23})
                    EXPECT_NEAR(r.image.at(x, y).w, want, tol) << what << " at " << x << "," << y;
        }
}

TEST_P(Clipping, PlanesThatKeepNothingOrEverything) {
    const PreparedMesh pm = constantCube();
    for (const RenderMethod m : testing::kEveryMethod) {
        const std::string what = methodName(m);
        // Parallel to the rays, on the kept side: nothing is cut; on the other: nothing is left.
        RenderSettings s = clipViewAlongX(m, true);
        const RenderResult whole = render(pm, s);
        s.clipPlanes = {{Vec3f(0.f, 0.f, -5.f), Vec3f(0.f, 0.f, 1.f)}};
        EXPECT_TRUE(testing::samePixels(render(pm, s).image, whole.image)) << what;
        s.clipPlanes = {{Vec3f(0.f, 0.f, 5.f), Vec3f(0.f, 0.f, 1.f)}};
        for (const Vec4f& p : render(pm, s).image.pixels) ASSERT_EQ(p.w, 0.f) << what;
        // Two planes whose kept sides do not meet.
        s.clipPlanes = {{Vec3f(0.6f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)},
                        {Vec3f(0.7f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
        for (const Vec4f& p : render(pm, s).image.pixels) ASSERT_EQ(p.w, 0.f) << what;
        // A slab between them: 0.1 of the chord.
        s.clipPlanes = {{Vec3f(0.7f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)},
                        {Vec3f(0.6f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
        EXPECT_NEAR(render(pm, s).image.at(12, 8).w, -std::expm1(-0.05),
                    m == RenderMethod::Exact ? 1e-4 : 6e-3)
            << what;
    }
}

TEST_P(Clipping, ABoxAroundTheMeshChangesNothing) {
    // The sampling methods take the same samples (bit for bit); the exact method stops where
    // the box's exit is, which is the mesh's own to rounding.
    const PreparedMesh pm = wavyCube();
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = clipViewAlongX(m, false, "0:0,0.5:0.8,1:0.3");
        s.camera = orbitCamera(*s.camera, 25.f, 30.f);
        const RenderResult whole = render(pm, s);
        s.clipBox = Bounds3f{Vec3f(-1.f, -1.f, -1.f), Vec3f(2.f, 2.f, 2.f)};
        const RenderResult boxed = render(pm, s);
        if (m != RenderMethod::Exact) {
            EXPECT_TRUE(testing::samePixels(boxed.image, whole.image)) << methodName(m);
            continue;
        }
        for (std::size_t i = 0; i < whole.image.pixels.size(); ++i)
            for (int c = 0; c < 4; ++c)
                ASSERT_NEAR(boxed.image.pixels[i][c], whole.image.pixels[i][c], 1e-5f)
                    << "pixel " << i;
    }
}

TEST_P(Clipping, TheTwoHalvesOfACutCompositeToTheWhole) {
    // Exact: along rays that cross x = c once going +x, the half x <= c over the half x >= c is
    // the whole (front-to-back compositing of one integral split at the plane).
    const PreparedMesh pm = wavyCube();
    RenderSettings s = clipViewAlongX(RenderMethod::Exact, false, "0:0,0.5:0.8,1:0.3");
    const RenderResult whole = render(pm, s);
    s.clipPlanes = {{Vec3f(0.43f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)}};
    const RenderResult nearHalf = render(pm, s);
    s.clipPlanes = {{Vec3f(0.43f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
    const RenderResult farHalf = render(pm, s);
    float worst = 0.f;
    for (std::size_t i = 0; i < whole.image.pixels.size(); ++i) {
        const Vec4f a = nearHalf.image.pixels[i], b = farHalf.image.pixels[i];
        for (int c = 0; c < 4; ++c)
            worst =
                std::max(worst, std::fabs(a[c] + (1.f - a.w) * b[c] - whole.image.pixels[i][c]));
    }
    EXPECT_LT(worst, 2e-4f);
    // Neither half is the whole.
    EXPECT_GT(whole.image.at(12, 8).w, nearHalf.image.at(12, 8).w + 0.01f);
    EXPECT_GT(whole.image.at(12, 8).w, farHalf.image.at(12, 8).w + 0.01f);
}

TEST_P(Clipping, TheCutFaceShowsTheFieldWhereThePlaneCutsIt) {
    // A linear field (which trilinear hexahedra and tetrahedra reproduce exactly), cut at
    // x = 0.43. Keeping x >= 0.43, every ray of the parallel view along +x meets the cut face
    // first: with clip_surface the pixel is the transfer function's colour at the field's value
    // there, lit head-on (ambient 0 + diffuse 1: the colour itself), opaque. Keeping x <= 0.43,
    // the face ends the rays: the volume in front composites over it.
    const auto field = [](Vec3f p) { return p.x + 0.5f * p.y + 0.25f * p.z; };
    for (const bool split : {false, true}) {
        PrepareOptions options;
        options.kd.leafCells = 32;
        options.cells.splitCells = split;
        const Mesh m = testing::makeHexGrid(6, 0.f, 1.f, field);
        const PreparedMesh pm = prepareMesh(m, selectScalarField(m, {}), options);
        for (const RenderMethod method : testing::kEveryMethod) {
            const std::string what =
                std::string(methodName(method)) + (split ? " tetrahedra" : " hexahedra");
            RenderSettings s = clipViewAlongX(method, true, "constant:1");
            s.clipSurface = true;
            s.clipPlanes = {{Vec3f(0.43f, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
            const RenderResult front = render(pm, s);
            // The colour at pixel (x, y): the view's right is -y, its up +z, 0.025 a pixel.
            auto faceColour = [&](int x, int y) {
                const Vec3f p(0.43f, 0.52f - (float(x) + 0.5f - 12.f) * 0.025f,
                              0.47f + (8.f - (float(y) + 0.5f)) * 0.025f);
                return s.tf.colorAt((field(p) - s.range->first) /
                                    (s.range->second - s.range->first));
            };
            float worst = 0.f;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const Vec4f c = front.image.at(x, y);
                    const Vec3f want = faceColour(x, y);
                    EXPECT_EQ(c.w, 1.f) << what;
                    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(c[k] - want[k]));
                }
            EXPECT_LT(worst, 3.f / 255.f) << what;
            // The other side: the volume x in [0, 0.43] over the face.
            s.clipPlanes = {{Vec3f(0.43f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)}};
            const RenderResult behind = render(pm, s);
            s.clipSurface = false;
            const RenderResult volume = render(pm, s);
            worst = 0.f;
            for (int y = 0; y < s.height; ++y)
                for (int x = 0; x < s.width; ++x) {
                    const Vec4f v = volume.image.at(x, y), c = behind.image.at(x, y);
                    const Vec3f want = faceColour(x, y);
                    EXPECT_LT(v.w, 0.9f) << what;  // the face shows through
                    EXPECT_EQ(c.w, 1.f) << what;
                    for (int k = 0; k < 3; ++k)
                        worst = std::max(worst, std::fabs(c[k] - (v[k] + (1.f - v.w) * want[k])));
                }
            EXPECT_LT(worst, 3.f / 255.f) << what;
        }
    }
}

TEST(ClipSettings, BadPlanesAndBoxesAreRefusedNamingThem) {
    RenderSettings s;
    s.tf = transferFunctionPreset("viridis");
    s.clipPlanes.assign(kMaxClipPlanes + 1, ClipPlane{});
    EXPECT_THROW(validateSettings(s), SettingError);
    s.clipPlanes = {{Vec3f(0.f, 0.f, 0.f), Vec3f(0.f, 0.f, 0.f)}};
    try {
        validateSettings(s);
        ADD_FAILURE() << "a zero normal was accepted";
    } catch (const SettingError& e) {
        EXPECT_EQ(e.setting(), "clip_planes");
        EXPECT_EQ(e.value(), "0,0,0,0,0,0");
    }
    s.clipPlanes = {{Vec3f(NAN, 0.f, 0.f), Vec3f(1.f, 0.f, 0.f)}};
    EXPECT_THROW(validateSettings(s), SettingError);
    s.clipPlanes.clear();
    s.clipBox = Bounds3f{Vec3f(1.f, 0.f, 0.f), Vec3f(0.f, 1.f, 1.f)};
    try {
        validateSettings(s);
        ADD_FAILURE() << "an inverted box was accepted";
    } catch (const SettingError& e) {
        EXPECT_EQ(e.setting(), "clip_box");
    }
    s.clipBox = Bounds3f{Vec3f(0.f, 0.f, 0.f), Vec3f(1.f, 1.f, 1.f)};
    EXPECT_NO_THROW(validateSettings(s));
}

TEST(ClipSettings, PlanesMoveWithTheMeshFrame) {
    // A mesh rendered scaled and shifted (MeshFrame): the planes and the box follow, the normals
    // become unit vectors.
    RenderSettings s;
    s.clipPlanes = {{Vec3f(1e7f + 2.f, 0.f, 0.f), Vec3f(2.f, 0.f, 0.f)}};
    s.clipBox = Bounds3f{Vec3f(1e7f, 0.f, 0.f), Vec3f(1e7f + 4.f, 1.f, 1.f)};
    MeshFrame frame;
    frame.origin = Vec3f(1e7f, 0.f, 0.f);
    frame.scale = 0.5;
    const ClipView v = clipView(s, frame);
    ASSERT_EQ(v.planeCount, 1);
    EXPECT_FLOAT_EQ(v.planes[0].origin.x, 1.f);
    EXPECT_FLOAT_EQ(v.planes[0].normal.x, 1.f);
    ASSERT_TRUE(v.hasBox);
    EXPECT_FLOAT_EQ(v.box.lo.x, 0.f);
    EXPECT_FLOAT_EQ(v.box.hi.x, 2.f);
    EXPECT_FLOAT_EQ(v.box.hi.y, 0.5f);
}

}  // namespace
}  // namespace uvr

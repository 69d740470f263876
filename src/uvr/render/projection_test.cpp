// SPDX-License-Identifier: MIT
// Parallel projection and supersampling end to end on the CPU: analytic silhouettes of a box
// (parallel rays cross the same depth everywhere), sub-pixel coverage of its edges, and the one
// ray per pixel of --supersample 1, with all three integrators.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/render/frame_kernel.h"
#include "uvr/render/frame_setup.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {
namespace {

/// The unit cube [0, 1]^3 of 2^3 hexahedra, constant field 1, with partitions and the mesh BVH.
PreparedMesh unitCube() {
    const Mesh m = testing::makeHexGrid(2, 0.f, 1.f);
    PrepareOptions o;
    o.kd.leafCells = 8;
    return prepareMesh(m, selectScalarField(m, {}), o);
}

/// Constant opacity 0.5 per unit length 1 over the cube's field, nothing terminating early.
RenderSettings halfOpacity(RenderMethod method) {
    RenderSettings s;
    s.method = method;
    s.tf = transferFunctionPreset("grayscale");
    applyOpacitySpec(s.tf, "constant:0.5");
    s.range = std::pair{0.f, 2.f};
    s.opacityUnit = 1.f;
    s.terminationAlpha = 1.f;
    return s;
}

/// Alpha of a ray crossing the unit cube along an axis: opacity 0.5 per unit 1 over 1 (the default
/// law).
const float kThroughAlpha = float(testing::slabOpacity(0.5, 1.0, 1.0));
/// Tolerance on it: the sample-based methods' last sample owns up to a step (1/148 of the
/// cube's diagonal by default) past the mesh, at most 0.6 / 148 of alpha.
constexpr float kAlphaTol = 5e-3f;

/// A parallel camera looking down -z at (cx, cy) with 2 * scale world units over `height`
/// pixels.
Camera parallelDownZ(float cx, float cy, float scale) {
    Camera c;
    c.position = {cx, cy, 3.f};
    c.focalPoint = {cx, cy, 0.5f};
    c.viewUp = {0.f, 1.f, 0.f};
    c.parallelProjection = true;
    c.parallelScale = scale;
    return c;
}

/// The frames of these suites render on every device (tests/on_each_device.h).
class CameraRender : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(CameraRender);
class Supersample : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Supersample);

TEST_P(CameraRender, ParallelSilhouetteOfABoxIsItsRectangleOfPixels) {
    // 40 x 30 pixels of 0.05 (scale 0.75) centred on the cube's centre: the image spans x in
    // [-0.5, 1.5] and y in [-0.25, 1.25], so the cube covers columns 10..29 and rows 5..24
    // exactly, its faces on pixel boundaries; every ray inside crosses depth 1.
    const PreparedMesh mesh = unitCube();
    for (RenderMethod method : testing::kEveryMethod) {
        RenderSettings s = halfOpacity(method);
        s.width = 40, s.height = 30;
        s.camera = parallelDownZ(0.5f, 0.5f, 0.75f);
        const RenderResult r = render(mesh, s);
        int wrong = 0;
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const bool inside = x >= 10 && x < 30 && y >= 5 && y < 25;
                const float a = r.image.pixels[std::size_t(y) * s.width + x].w;
                const bool ok = inside ? std::fabs(a - kThroughAlpha) <= kAlphaTol : a == 0.f;
                if (!ok && ++wrong <= 5)
                    ADD_FAILURE() << methodName(method) << ": pixel (" << x << ", " << y
                                  << ") alpha " << a << (inside ? " inside" : " outside");
            }
        EXPECT_EQ(wrong, 0) << methodName(method);
    }
}

TEST_P(CameraRender, ParallelCameraInsideOrFarFromTheMeshSeesWhatLiesInFrontOfItsPlane) {
    const PreparedMesh mesh = unitCube();
    for (RenderMethod method : testing::kEveryMethod) {
        RenderSettings s = halfOpacity(method);
        s.width = s.height = 8;
        // Far out: the rays start at the mesh (the same image as from near by).
        s.camera = parallelDownZ(0.5f, 0.5f, 0.25f);
        s.camera->position.z = 1e6f;
        const RenderResult far = render(mesh, s);
        for (const Vec4f& p : far.image.pixels)
            EXPECT_NEAR(p.w, kThroughAlpha, kAlphaTol) << methodName(method);
        // Inside, at z = 0.25 looking down -z: only the quarter of the depth in front of the
        // camera's plane is seen (VTK's near plane never lies behind the camera).
        s.camera->position.z = 0.25f;
        s.camera->focalPoint.z = -3.f;
        const RenderResult inside = render(mesh, s);
        const float quarter = float(testing::slabOpacity(0.5, 0.25, 1.0));
        for (const Vec4f& p : inside.image.pixels)
            EXPECT_NEAR(p.w, quarter, kAlphaTol) << methodName(method);
        // Behind the mesh, looking away from it: nothing.
        s.camera->position.z = -0.5f;
        s.camera->focalPoint.z = -3.f;
        const RenderResult away = render(mesh, s);
        for (const Vec4f& p : away.image.pixels) EXPECT_EQ(p.w, 0.f) << methodName(method);
    }
}

TEST_P(CameraRender, ParallelCameraIsConvertedToAFramedMeshsUnits) {
    // A cube moved to x = 1e5, and one scaled to 1e-9, render in frames of their own (moved to
    // the centre, scaled up): a parallel camera given in file units, its scale too, must see
    // them as it sees the unit cube.
    struct Case {
        const char* name;
        float offset, size;
    };
    for (const Case c : {Case{"moved", 1e5f, 1.f}, Case{"tiny", 0.f, 1e-9f}}) {
        Mesh m = testing::makeHexGrid(2, 0.f, 1.f);
        for (Vec3f& p : m.points) p = Vec3f(p.x * c.size + c.offset, p.y * c.size, p.z * c.size);
        const PreparedMesh mesh = prepareMesh(m, selectScalarField(m, {}));
        ASSERT_FALSE(mesh.tets.frame.identity()) << c.name;
        RenderSettings s = halfOpacity(RenderMethod::Exact);
        s.opacityUnit = c.size;
        s.width = 40, s.height = 30;
        Camera cam = parallelDownZ(0.5f, 0.5f, 0.75f);
        cam.position = Vec3f(cam.position.x * c.size + c.offset, cam.position.y * c.size,
                             cam.position.z * c.size);
        cam.focalPoint = Vec3f(cam.focalPoint.x * c.size + c.offset, cam.focalPoint.y * c.size,
                               cam.focalPoint.z * c.size);
        cam.parallelScale *= c.size;
        s.camera = cam;
        const RenderResult r = render(mesh, s);
        int wrong = 0;
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const bool inside = x >= 10 && x < 30 && y >= 5 && y < 25;
                const float a = r.image.pixels[std::size_t(y) * s.width + x].w;
                if (inside ? !(std::fabs(a - kThroughAlpha) <= kAlphaTol) : a != 0.f)
                    if (++wrong <= 5)
                        ADD_FAILURE() << c.name << ": pixel (" << x << ", " << y << ") alpha " << a;
            }
        EXPECT_EQ(wrong, 0) << c.name;
    }
}

TEST(SupersampleRays, OneRayPerPixelIsTheCentreRayBitForBit) {
    // --supersample 1 (the default) must be the single-ray image: every pixel equal, bit for
    // bit, to its centre ray marched alone (on the CPU: the same compiler's code), and its count
    // that ray's samples.
    const PreparedMesh mesh = unitCube();
    for (RenderMethod method : {RenderMethod::Reference, RenderMethod::Exact}) {
        RenderSettings s = halfOpacity(method);
        s.width = 13, s.height = 9;
        s.camera = orbitCamera(resetCamera(mesh.tets.bounds, 13.f / 9.f), 25.f, 15.f);
        const RenderResult r = renderCpu(mesh, s);
        const SceneView scene = r.setup.scene(mesh);
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                RayCounters c;
                const Ray ray = r.setup.rays.ray(float(x) + 0.5f, float(y) + 0.5f);
                const Vec4f want = method == RenderMethod::Exact ? integrateExact(scene, ray, c)
                                                                 : marchReference(scene, ray, c);
                const std::size_t i = std::size_t(y) * s.width + x;
                EXPECT_EQ(std::memcmp(&want, &r.image.pixels[i], sizeof want), 0)
                    << methodName(method) << " pixel " << x << ", " << y;
                EXPECT_EQ(r.sampleCounts[i], c.samples);
            }
    }
}

TEST_P(Supersample, EdgePixelsApproachTheTrueFractionalCoverage) {
    // The parallel view of the cube shifted by 0.3 of a pixel to the left and 0.4 down: its left
    // edge crosses column 10 at 0.3 of the column's width (0.7 of it covered, the centre
    // inside) and its top edge crosses row 4 at 0.6 of the row's height from its top (0.4
    // covered, the centre outside), the corner pixel (10, 4) is covered 0.28. One ray per pixel
    // sees all or nothing (a jagged edge); N x N rays see the covered fraction to within about
    // 1/N (stratified: at most 1/(2N) per axis), jittered ones within about 2/N.
    const PreparedMesh mesh = unitCube();
    const float pixel = 0.05f;
    for (RenderMethod method : testing::kEveryMethod) {
        for (int n : {1, 4, 8}) {
            for (bool jitter : {false, true}) {
                if (n == 1 && jitter) continue;
                RenderSettings s = halfOpacity(method);
                s.width = 40, s.height = 30;
                s.supersample = n;
                s.jitter = jitter;
                s.camera = parallelDownZ(0.5f - 0.3f * pixel, 0.5f - 0.4f * pixel, 0.75f);
                const RenderResult r = render(mesh, s);
                const auto coverage = [&](int x, int y) {
                    return r.image.pixels[std::size_t(y) * s.width + x].w / kThroughAlpha;
                };
                const std::string what = std::string(methodName(method)) +
                                         " N=" + std::to_string(n) + (jitter ? " jittered" : "");
                const float tol = (n == 1 ? 0.f : (jitter ? 2.f : 1.f) / float(n)) + 0.015f;
                const float want[3] = {n == 1 ? 1.f : 0.7f, n == 1 ? 0.f : 0.4f,
                                       n == 1 ? 0.f : 0.28f};
                EXPECT_NEAR(coverage(10, 15), want[0], tol) << what << " left edge";
                EXPECT_NEAR(coverage(20, 4), want[1], tol) << what << " top edge";
                EXPECT_NEAR(coverage(10, 4), want[2], tol) << what << " corner";
                EXPECT_NEAR(coverage(20, 15), 1.f, 0.015f) << what << " inside";
                EXPECT_EQ(coverage(5, 15), 0.f) << what << " outside";
                // Sample counts sum the rays of each pixel.
                EXPECT_EQ(r.stats.supersample, n);
                EXPECT_EQ(r.stats.rays(), std::uint64_t(40 * 30 * n * n));
                std::uint64_t sum = 0;
                for (std::uint32_t c : r.sampleCounts) sum += c;
                EXPECT_EQ(sum, r.stats.samples) << what;
            }
        }
    }
}

TEST_P(Supersample, StatedExactlyForTheReferenceMarcher) {
    // The reference marcher takes the same samples along every axis-parallel ray through the
    // cube: each inside pixel's count is N^2 times one ray's.
    const PreparedMesh mesh = unitCube();
    RenderSettings s = halfOpacity(RenderMethod::Reference);
    s.width = 40, s.height = 30;
    s.camera = parallelDownZ(0.5f, 0.5f, 0.75f);
    const RenderResult one = render(mesh, s);
    s.supersample = 3;
    const RenderResult nine = render(mesh, s);
    const std::size_t centre = std::size_t(15) * s.width + 20;
    EXPECT_EQ(nine.sampleCounts[centre], 9u * one.sampleCounts[centre]);
    EXPECT_NEAR(nine.stats.meanSamplesPerRay(), one.stats.meanSamplesPerRay(), 1e-9);
    EXPECT_NEAR(nine.stats.meanSamplesPerPixel(), 9.0 * one.stats.meanSamplesPerPixel(), 1e-9);
}

TEST(SupersampleSetup, OutOfRangeIsRefusedAndCountsInTheWorkEstimate) {
    const PreparedMesh mesh = unitCube();
    RenderSettings s = halfOpacity(RenderMethod::Reference);
    s.width = s.height = 8;
    for (int n : {0, 9, -1}) {
        s.supersample = n;
        const Error e = testing::catchError([&] { (void)makeFrameSetup(mesh, s); });
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        // The library names the setting in neutral words (each front end re-spells it).
        EXPECT_EQ(std::string(e.what()),
                  "supersample " + std::to_string(n) + ": expected an integer in [1, 8]");
    }
    // 16384^2 pixels x 64 rays x 100 samples per ray is beyond 10^12 samples.
    s.width = s.height = 16384;
    s.supersample = 8;
    s.step = std::sqrt(3.f) / 100.f;
    const Error e = testing::catchError([&] { (void)makeFrameSetup(mesh, s); });
    EXPECT_NE(std::string(e.what()).find("64 rays (`supersample` 8)"), std::string::npos)
        << e.what();
    s.supersample = 1;
    EXPECT_NO_THROW((void)makeFrameSetup(mesh, s));
}

TEST(SupersampleSetup, ProgressStillAdvancesToOne) {
    const PreparedMesh mesh = unitCube();
    RenderSettings s = halfOpacity(RenderMethod::Reference);
    s.width = s.height = 64;
    s.supersample = 4;
    std::vector<double> reports;
    s.progress = [&](double f) { reports.push_back(f); };
    (void)renderCpu(mesh, s);
    ASSERT_FALSE(reports.empty());
    EXPECT_EQ(reports.back(), 1.0);
    for (std::size_t i = 1; i < reports.size(); ++i) EXPECT_GT(reports[i], reports[i - 1]);
}

}  // namespace
}  // namespace uvr

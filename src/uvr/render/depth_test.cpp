// SPDX-License-Identifier: MIT
// Depth in and out (issue 32) in every method and on every device. Oracles: the distance of an
// opaque plane (a linear field's isosurface) along the view direction; where a slab of constant
// extinction reaches an opacity, in closed form; a depth image given in equal to a clip at its
// plane; the .npy files numpy writes and reads; a per-pixel stop opacity (a data-parallel
// frame's second pass) against the slab's extinction, and a per-pixel depth opacity against
// frames asking that opacity of every pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <string>

#include "on_each_device.h"
#include "render_scenes.h"
#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/output_file.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/render/camera.h"
#include "uvr/render/depth_image.h"
#include "uvr/render/frame_setup.h"

namespace uvr {
namespace {

PreparedMesh linearCube(bool split) {
    const Mesh m = testing::makeHexGrid(6, 0.f, 1.f, testing::linearField);
    PrepareOptions options;
    options.kd.leafCells = 32;
    options.cells.splitCells = split;
    return prepareMesh(m, selectScalarField(m, {}), options);
}

/// A parallel view along +x from x = -2 over the middle of the unit cube: a ray's view depth is
/// its x + 2.
RenderSettings depthViewAlongX(RenderMethod method) {
    RenderSettings s;
    s.method = method;
    s.width = 16, s.height = 12;
    Camera c;
    c.position = Vec3f(-2.f, 0.5f, 0.5f);
    c.focalPoint = Vec3f(0.5f, 0.5f, 0.5f);
    c.viewUp = Vec3f(0.f, 0.f, 1.f);
    c.parallelProjection = true;
    c.parallelScale = 0.3f;
    s.camera = c;
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "constant:1");
    s.range = {-0.5f, 1.2f};
    s.opacityUnit = 0.5f;  // extinction 2 per unit
    s.opacityLaw = OpacityLaw::Attenuation;
    s.step = 0.01f;
    return s;
}

class Depth : public testing::OnEachDevice {};
UVR_ON_EACH_DEVICE(Depth);

TEST_P(Depth, ASlabReachesTheOpacityWhereItsExtinctionSays) {
    // Extinction 2 per unit from x = 0: the opacity reaches a at x = -ln(1 - a) / 2, view depth
    // 2 + that; within a step s1 = 0.01 for the sampling methods. Supersampled: the nearest of a
    // pixel's rays, the same here.
    for (const bool split : {true, false}) {
        const PreparedMesh pm = linearCube(split);
        for (const RenderMethod m : testing::kEveryMethod)
            for (const float a : {0.5f, 0.8f})
                for (const int n : {1, 2}) {
                    RenderSettings s = depthViewAlongX(m);
                    s.depthAlpha = a;
                    s.supersample = n;
                    const RenderResult r = render(pm, s);
                    ASSERT_EQ(r.depth.size(), r.image.pixels.size());
                    const float want = 2.f - std::log(1.f - a) / 2.f;
                    const float tol = m == RenderMethod::Exact ? 1e-4f : 0.011f;
                    for (const float z : r.depth)
                        ASSERT_NEAR(z, want, tol) << methodName(m) << " opacity " << a;
                }
    }
}

TEST_P(Depth, AnOpaqueIsosurfaceIsWhereThePlaneIs) {
    // Transparent volume, an opaque plane g . p = c: each ray's depth is where it meets the
    // plane, x + 2 with x = (c - g.y y - g.z z) / g.x, exact to 1e-4, sampled within s1.
    const float c = 0.45f;
    const Vec3f g = testing::kLinearGradient;
    const PreparedMesh pm = linearCube(true);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = depthViewAlongX(m);
        applyOpacitySpec(s.tf, "constant:0");
        s.isoSurfaces = {IsoSurface{c}};
        s.depthAlpha = 0.5f;
        const RenderResult r = render(pm, s);
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const Ray ray = r.setup.rays.ray(float(x) + 0.5f, float(y) + 0.5f);
                const float hit = (c - g.y * ray.org.y - g.z * ray.org.z) / g.x;
                const float tol = m == RenderMethod::Exact ? 1e-4f : 0.011f;
                const float z = r.depth[std::size_t(y) * s.width + x];
                if (hit > 0.02f && hit < 0.98f) {
                    EXPECT_NEAR(z, hit + 2.f, tol) << methodName(m) << " at " << x << "," << y;
                } else if (hit > 1.02f) {  // the plane lies beyond the cube
                    EXPECT_EQ(z, INFINITY) << methodName(m) << " at " << x << "," << y;
                }
            }
    }
    // Nothing reached: infinity.
    RenderSettings s = depthViewAlongX(RenderMethod::Exact);
    applyOpacitySpec(s.tf, "constant:0");
    s.depthAlpha = 0.5f;
    for (const float z : render(pm, s).depth) EXPECT_EQ(z, INFINITY);
}

TEST_P(Depth, GeometryGivenAsDepthEndsTheRaysAsAClipWould) {
    // Opaque geometry at view depth 2.4 (x = 0.4) everywhere but one column: the frame equals
    // the one clipped at x = 0.4 (the exact integrator cuts the cell there), and where the
    // depth is infinite or NaN the unclipped one, bit for bit.
    const PreparedMesh pm = linearCube(true);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = depthViewAlongX(m);
        applyOpacitySpec(s.tf, "constant:0.3");
        const RenderResult whole = render(pm, s);
        RenderSettings clipped = s;
        clipped.clipPlanes = {{Vec3f(0.4f, 0.f, 0.f), Vec3f(-1.f, 0.f, 0.f)}};
        const RenderResult cut = render(pm, clipped);
        s.depthIn.assign(std::size_t(s.width) * s.height, 2.4f);
        for (int y = 0; y < s.height; ++y) s.depthIn[std::size_t(y) * s.width] = INFINITY;
        s.depthIn[1] = NAN;
        const RenderResult r = render(pm, s);
        const float tol = m == RenderMethod::Exact ? 2e-4f : 0.011f;
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const Vec4f got = r.image.at(x, y);
                const bool none = x == 0 || (x == 1 && y == 0);
                const Vec4f want = none ? whole.image.at(x, y) : cut.image.at(x, y);
                if (none) {
                    EXPECT_EQ(std::memcmp(&got, &want, sizeof got), 0) << methodName(m);
                } else {
                    for (int k = 0; k < 4; ++k)
                        EXPECT_NEAR(got[k], want[k], tol) << methodName(m) << " at " << x;
                }
            }
        EXPECT_LT(r.image.at(8, 6).w, whole.image.at(8, 6).w - 0.1f) << methodName(m);
    }
}

TEST_P(Depth, APixelsStopOpacityEndsItsRayThere) {
    // Stop in (a data-parallel frame's second pass): each pixel's ray stops at its own opacity,
    // which the slab's extinction (2 per unit, steps of 0.01: 0.02 of what is left per step)
    // overshoots by less than one step; a pixel with stop 0 is not rendered. Exact runs on.
    const PreparedMesh pm = linearCube(true);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = depthViewAlongX(m);
        s.terminationAlpha = 1.f;
        const float full = render(pm, s).image.at(8, 6).w;  // about 1 - exp(-2)
        s.pixelStopAlpha.assign(std::size_t(s.width) * s.height, 0.f);
        for (int y = 0; y < s.height; ++y)
            for (int x = 1; x < s.width; ++x)
                s.pixelStopAlpha[std::size_t(y) * s.width + x] = x % 2 ? 0.3f : 0.6f;
        const RenderResult r = render(pm, s);
        for (int y = 0; y < s.height; ++y) {
            EXPECT_EQ(r.image.at(0, y).w, 0.f) << methodName(m);
            EXPECT_EQ(r.sampleCounts[std::size_t(y) * s.width], 0u) << methodName(m);
            for (int x = 1; x < s.width; ++x) {
                const float a = r.image.at(x, y).w, stop = x % 2 ? 0.3f : 0.6f;
                if (m == RenderMethod::Exact) {
                    EXPECT_NEAR(a, full, 1e-5f) << " at " << x << ", " << y;
                } else {
                    // The adaptive method's steps are longer in the constant field: it stops
                    // after the step that reaches the stop, short of the slab's end.
                    const float over = m == RenderMethod::Reference ? 0.021f : 0.2f;
                    EXPECT_GE(a, stop) << methodName(m) << " at " << x << ", " << y;
                    EXPECT_LT(a, stop + over * (1.f - stop))
                        << methodName(m) << " at " << x << ", " << y;
                    EXPECT_LT(a, full - 0.1f) << methodName(m);
                }
            }
        }
    }
    // Bad stops are setting errors.
    RenderSettings s = depthViewAlongX(RenderMethod::Reference);
    s.pixelStopAlpha.assign(15, 0.5f);
    EXPECT_THROW(checkDepth(s), SettingError);
    s.pixelStopAlpha.assign(std::size_t(s.width) * s.height, 0.5f);
    EXPECT_NO_THROW(checkDepth(s));
    s.pixelStopAlpha[3] = 1.5f;
    EXPECT_THROW(checkDepth(s), SettingError);
    s.pixelStopAlpha[3] = NAN;
    EXPECT_THROW(checkDepth(s), SettingError);
    s.pixelStopAlpha[3] = 0.5f;
    s.supersample = 2;
    EXPECT_THROW(checkDepth(s), SettingError);
}

TEST_P(Depth, APixelsDepthOpacityIsWhereItsRayReachesIt) {
    // Depth alpha in (a data-parallel frame's second pass): each pixel's ray notes the depth of
    // its own opacity, exactly where a frame asking that opacity of every pixel notes it; 0: no
    // depth there. The colours are the frame's without it.
    const PreparedMesh pm = linearCube(true);
    for (const RenderMethod m : testing::kEveryMethod) {
        RenderSettings s = depthViewAlongX(m);
        s.depthAlpha = 0.5f;
        const RenderResult plain = render(pm, s);
        s.depthAlpha = 0.3f;
        const RenderResult at3 = render(pm, s);
        s.depthAlpha = 0.6f;
        const RenderResult at6 = render(pm, s);
        s.pixelDepthAlpha.assign(std::size_t(s.width) * s.height, 0.f);
        for (int y = 0; y < s.height; ++y)
            for (int x = 1; x < s.width; ++x)
                s.pixelDepthAlpha[std::size_t(y) * s.width + x] = x % 2 ? 0.3f : 0.6f;
        const RenderResult r = render(pm, s);
        for (int y = 0; y < s.height; ++y)
            for (int x = 0; x < s.width; ++x) {
                const std::size_t i = std::size_t(y) * s.width + x;
                SCOPED_TRACE(std::string(methodName(m)) + " at " + std::to_string(x) + ", " +
                             std::to_string(y));
                if (x == 0)
                    EXPECT_FALSE(r.depth[i] < INFINITY);
                else
                    EXPECT_EQ(r.depth[i], (x % 2 ? at3 : at6).depth[i]);
                EXPECT_EQ(r.image.pixels[i].w, plain.image.pixels[i].w);
            }
    }
    // Bad opacities are setting errors, and depth alpha in needs depth out.
    RenderSettings s = depthViewAlongX(RenderMethod::Reference);
    s.depthAlpha = 0.5f;
    s.pixelDepthAlpha.assign(15, 0.5f);
    EXPECT_THROW(checkDepth(s), SettingError);
    s.pixelDepthAlpha.assign(std::size_t(s.width) * s.height, 0.5f);
    EXPECT_NO_THROW(checkDepth(s));
    s.pixelDepthAlpha[3] = -0.5f;
    EXPECT_THROW(checkDepth(s), SettingError);
    s.pixelDepthAlpha[3] = 0.5f;
    s.depthAlpha = 0.f;
    EXPECT_THROW(checkDepth(s), SettingError);
}

TEST(DepthImage, NpyRoundTripsAndBadFilesAreNamed) {
    const std::string dir = testing::scratchDir();
    const std::vector<float> depth = {1.f, 2.5f, INFINITY, -3.f, 0.f, 7.f};
    {
        OutputFile out(dir + "/d.npy");
        writeDepthNpy(out, 3, 2, depth);
        out.commit();
    }
    const std::vector<float> back = readDepthNpy(dir + "/d.npy", 3, 2);
    EXPECT_EQ(std::memcmp(back.data(), depth.data(), depth.size() * sizeof(float)), 0);
    // NumPy's own header form: version 1.0, the header a multiple of 64 bytes with the preamble.
    std::ifstream in(dir + "/d.npy", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
    EXPECT_EQ((bytes.size() - depth.size() * 4) % 64, 0u);
    EXPECT_NE(bytes.find("'shape': (2, 3)"), std::string::npos);
    auto message = [&](const std::string& path, int w, int h) {
        return std::string(testing::catchError([&] { readDepthNpy(path, w, h); }).what());
    };
    EXPECT_NE(message(dir + "/d.npy", 2, 3).find("shape (2, 3), but the frame is 2x3"),
              std::string::npos);
    auto craft = [&](const std::string& name, const std::string& text) {
        return testing::writeFile(dir + "/" + name, text);
    };
    const std::string head = std::string("\x93NUMPY\x01\x00", 8);
    auto npy = [&](const std::string& dict, std::size_t dataBytes) {
        std::string h = dict;
        h.append((10 + h.size() + 1 + 63) / 64 * 64 - 10 - h.size() - 1, ' ');
        h += '\n';
        std::string s = head;
        s += char(h.size() & 0xff);
        s += char(h.size() >> 8);
        return s + h + std::string(dataBytes, '\0');
    };
    EXPECT_NE(message(craft("a.npy", "hello"), 3, 2).find("not a NumPy .npy"), std::string::npos);
    EXPECT_NE(message(craft("b.npy", npy("{'descr': '<i4', 'fortran_order': False, 'shape': "
                                         "(2, 3), }",
                                         24)),
                      3, 2)
                  .find("dtype '<i4'"),
              std::string::npos);
    EXPECT_NE(message(craft("c.npy", npy("{'descr': '<f4', 'fortran_order': True, 'shape': (2, "
                                         "3), }",
                                         24)),
                      3, 2)
                  .find("C order"),
              std::string::npos);
    EXPECT_NE(message(craft("d.npy", npy("{'descr': '<f4', 'fortran_order': False, 'shape': (2, "
                                         "3), }",
                                         20)),
                      3, 2)
                  .find("truncated"),
              std::string::npos);
    // float64 is read (converted).
    std::string f8 = npy("{'descr': '<f8', 'fortran_order': False, 'shape': (1, 2), }", 0);
    const double two[2] = {1.5, -2.0};
    f8.append(reinterpret_cast<const char*>(two), sizeof two);
    const std::vector<float> got = readDepthNpy(craft("e.npy", f8), 2, 1);
    EXPECT_EQ(got, (std::vector<float>{1.5f, -2.f}));
    // A depth image of the wrong size is a setting error.
    RenderSettings s;
    s.width = 4, s.height = 4;
    s.depthIn.assign(15, 1.f);
    EXPECT_THROW(checkDepth(s), SettingError);
    s.depthIn.clear();
    s.depthAlpha = 1.5f;
    EXPECT_THROW(checkDepth(s), SettingError);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// The command line's camera and anti-aliasing flags (issue 15): --parallel and
// --parallel-scale, parallel .pvcc files, the automatic view up, --supersample and --jitter,
// and what --stats says about them.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"
#include "uvr/render/image.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;

/// Writes the unit cube of five tetrahedra with the point field f = 1 into dir; its path.
std::string writeUnitCube(const std::string& dir) {
    return testing::writeFile(
        dir + "/cube.vtk",
        cli_testing::fiveTetCubeVtk(
            "POINT_DATA 8\nSCALARS f float 1\nLOOKUP_TABLE default\n1 1 1 1 1 1 1 1\n"));
}

nlohmann::json readJson(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

/// A ParaView camera file looking down -z at the unit cube's centre, parallel or not, with
/// CameraParallelScale `scale`.
std::string parallelPvcc(const std::string& dir, bool parallel, const std::string& scale) {
    return testing::writeFile(dir + (parallel ? "/parallel.pvcc" : "/perspective.pvcc"),
                              R"(<?xml version="1.0"?>
<PVCameraConfiguration description="ParaView camera configuration" version="1.0">
  <Proxy group="views" type="RenderView" id="1" servers="21">
    <Property name="CameraPosition" id="1.CameraPosition" number_of_elements="3">
      <Element index="0" value="0.5"/>
      <Element index="1" value="0.5"/>
      <Element index="2" value="4"/>
    </Property>
    <Property name="CameraFocalPoint" id="1.CameraFocalPoint" number_of_elements="3">
      <Element index="0" value="0.5"/>
      <Element index="1" value="0.5"/>
      <Element index="2" value="0.5"/>
    </Property>
    <Property name="CameraViewUp" id="1.CameraViewUp" number_of_elements="3">
      <Element index="0" value="0"/>
      <Element index="1" value="1"/>
      <Element index="2" value="0"/>
    </Property>
    <Property name="CameraViewAngle" id="1.CameraViewAngle" number_of_elements="1">
      <Element index="0" value="30"/>
    </Property>
    <Property name="CameraParallelScale" id="1.CameraParallelScale" number_of_elements="1">
      <Element index="0" value=")" +
                                  scale + R"("/>
    </Property>
    <Property name="CameraParallelProjection" id="1.CameraParallelProjection" number_of_elements="1">
      <Element index="0" value=")" +
                                  std::string(parallel ? "1" : "0") + R"("/>
    </Property>
  </Proxy>
</PVCameraConfiguration>
)");
}

/// Pixels with alpha above 0.1.
int covered(const Image& img) {
    int n = 0;
    for (const Vec4f& p : img.pixels) n += p.w > 0.1f;
    return n;
}

TEST(CliCamera, ParallelRendersTheCubesSquareAndStatesItsScale) {
    const std::string dir = testing::scratchDir();
    const std::string cube = writeUnitCube(dir);
    // --parallel with ParaView's reset: scale = the bounding sphere's radius, sqrt(3) / 2. The
    // cube seen face on is a square 1 / (2 radius) = 0.577 of the image height.
    const CliRun r = uvr("-q render " + cube +
                             " --parallel --size 60x60 --opacity constant:0.5 --method exact -o " +
                             dir + "/p.png --stats " + dir + "/p.json",
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = readJson(dir + "/p.json");
    EXPECT_EQ(j["camera"]["parallel_projection"], true);
    EXPECT_NEAR(j["camera"]["parallel_scale"].get<double>(), std::sqrt(3.0) / 2.0, 1e-6);
    const Image img = readPng(dir + "/p.png");
    const int side = static_cast<int>(std::lround(60.0 / std::sqrt(3.0)));  // 34.6 pixels
    EXPECT_NEAR(covered(img), side * side, 2 * 60);
    // Every covered pixel crossed the same depth: one alpha.
    float lo = 1.f, hi = 0.f;
    for (const Vec4f& p : img.pixels)
        if (p.w > 0.1f) lo = std::fmin(lo, p.w), hi = std::fmax(hi, p.w);
    EXPECT_LE(hi - lo, 2.f / 255.f);
    // --parallel-scale 1: the square is half the image height.
    ASSERT_EQ(uvr("-q render " + cube +
                      " --parallel --parallel-scale 1 --size 60x60 --opacity constant:0.5 -o " +
                      dir + "/q.png",
                  dir)
                  .code,
              0);
    EXPECT_NEAR(covered(readPng(dir + "/q.png")), 30 * 30, 2 * 30);
    // Perspective keeps its stats (no parallel scale).
    ASSERT_EQ(
        uvr("-q render " + cube + " --size 16x16 -o " + dir + "/v.png --stats " + dir + "/v.json",
            dir)
            .code,
        0);
    const auto v = readJson(dir + "/v.json");
    EXPECT_EQ(v["camera"]["parallel_projection"], false);
    EXPECT_FALSE(v["camera"].contains("parallel_scale"));
    EXPECT_EQ(v["camera"]["view_angle"], 30.f);
}

TEST(CliCamera, ParallelCameraFilesRoundTripThroughTheStats) {
    const std::string dir = testing::scratchDir();
    const std::string cube = writeUnitCube(dir) + " --opacity constant:0.5";
    const std::string pvcc = parallelPvcc(dir, true, "0.75");
    ASSERT_EQ(uvr("-q render " + cube + " --camera " + pvcc + " --size 40x30 -o " + dir +
                      "/c.png --stats " + dir + "/c.json",
                  dir)
                  .code,
              0);
    const auto c = readJson(dir + "/c.json")["camera"];
    EXPECT_EQ(c["parallel_projection"], true);
    EXPECT_FLOAT_EQ(c["parallel_scale"].get<float>(), 0.75f);
    EXPECT_FLOAT_EQ(c["position"][2].get<float>(), 4.f);
    EXPECT_FLOAT_EQ(c["focal_point"][0].get<float>(), 0.5f);
    // 0.05 per pixel: the cube is 20 x 20 pixels.
    EXPECT_NEAR(covered(readPng(dir + "/c.png")), 400, 40);
    // --parallel on a perspective file takes the file's scale; --parallel-scale overrides it.
    const std::string persp = parallelPvcc(dir, false, "0.75");
    ASSERT_EQ(uvr("-q render " + cube + " --camera " + persp + " --parallel --size 40x30 -o " +
                      dir + "/d.png --stats " + dir + "/d.json",
                  dir)
                  .code,
              0);
    EXPECT_FLOAT_EQ(readJson(dir + "/d.json")["camera"]["parallel_scale"].get<float>(), 0.75f);
    ASSERT_EQ(
        uvr("-q render " + cube + " --camera " + pvcc + " --parallel-scale 1.5 --size 40x30 -o " +
                dir + "/e.png --stats " + dir + "/e.json",
            dir)
            .code,
        0);
    EXPECT_FLOAT_EQ(readJson(dir + "/e.json")["camera"]["parallel_scale"].get<float>(), 1.5f);
    // --azimuth/--elevation orbit a parallel camera and keep it parallel.
    ASSERT_EQ(uvr("-q render " + cube + " --camera " + pvcc +
                      " --azimuth 30 --elevation 20 --size 40x30 -o " + dir + "/f.png --stats " +
                      dir + "/f.json",
                  dir)
                  .code,
              0);
    EXPECT_EQ(readJson(dir + "/f.json")["camera"]["parallel_projection"], true);
    // A parallel file without its scale, or with a bad one, names the file and the property.
    const std::string bad = parallelPvcc(dir, true, "0");
    expectOneLineError(
        uvr("-q render " + cube + " --camera " + bad + " -o " + dir + "/x.png", dir),
        {bad + ": line 22: property CameraParallelScale", "expected a positive parallel scale"},
        "zero scale");
}

TEST(CliCamera, MeaninglessParallelCombinationsAreRefusedInOneLine) {
    const std::string dir = testing::scratchDir();
    const std::string render =
        "-q render " + writeUnitCube(dir) + " --size 8x8 -o " + dir + "/o.png ";
    expectOneLineError(uvr(render + "--parallel --view-angle 20", dir),
                       {"--view-angle", "--parallel", "use --parallel-scale"}, "view angle");
    expectOneLineError(
        uvr(render + "--camera " + parallelPvcc(dir, true, "1") + " --view-angle 20", dir),
        {"--view-angle", "parallel.pvcc", "use --parallel-scale"},
        "view angle with a parallel file");
    expectOneLineError(uvr(render + "--parallel-scale 2", dir), {"--parallel-scale", "--parallel"},
                       "scale without --parallel");
    for (const char* scale : {"0", "-1", "nan"})
        expectOneLineError(uvr(render + "--parallel --parallel-scale " + scale, dir),
                           {"--parallel-scale"}, scale);
}

TEST(CliCamera, DefaultViewUpAlongTheViewDirectionIsReplacedWithANote) {
    const std::string dir = testing::scratchDir();
    const std::string render =
        "render " + writeUnitCube(dir) + " --size 16x16 --opacity constant:0.5 ";
    // Looking down -Y with the default up +Y: ParaView's "look along -Y" up, +Z, with a note.
    const CliRun r = uvr(render + "--camera-position 0.5,5,0.5 --camera-focal 0.5,0.5,0.5 -o " +
                             dir + "/y.png --stats " + dir + "/y.json",
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("uvr: note: the default view up 0,1,0 is parallel to the view direction "
                         "0,-1,0: using --camera-up 0,0,1"),
              std::string::npos)
        << r.err;
    const auto up = readJson(dir + "/y.json")["camera"]["view_up"];
    EXPECT_EQ(up[0], 0.f);
    EXPECT_EQ(up[1], 0.f);
    EXPECT_EQ(up[2], 1.f);
    EXPECT_GT(covered(readPng(dir + "/y.png")), 20);
    // Also when only the position is given (the focal point from the reset camera), and with an
    // orbit after it.
    EXPECT_EQ(
        uvr("-q " + render + "--camera-position 0.5,-7,0.5 --azimuth 10 -o " + dir + "/z.png", dir)
            .code,
        0);
    // A view up the user gave is refused with how to fix it.
    expectOneLineError(uvr("-q " + render +
                               "--camera-position 0.5,5,0.5 --camera-focal 0.5,0.5,0.5 "
                               "--camera-up 0,2,0 -o " +
                               dir + "/u.png",
                           dir),
                       {"--camera-up 0,2,0 is zero or parallel to the view direction 0,-1,0",
                        "pass a --camera-up across it, e.g. --camera-up 0,0,1"},
                       "explicit up");
    // So is a camera file's once --camera-position turns the view along it.
    const std::string pvcc = parallelPvcc(dir, false, "1");
    expectOneLineError(
        uvr("-q " + render + "--camera " + pvcc + " --camera-position 0.5,-3,0.5 -o " + dir +
                "/f.png",
            dir),
        {pvcc + ": view up 0,1,0 (CameraViewUp) is zero or parallel", "pass a --camera-up"},
        "file's up");
}

TEST(CliCamera, SupersampleAveragesRaysAndStatesItsCounts) {
    const std::string dir = testing::scratchDir();
    const std::string render = "-q render " + writeUnitCube(dir) +
                               " --size 24x16 --opacity constant:0.5 --method reference -o ";
    ASSERT_EQ(uvr(render + dir + "/one.png --stats " + dir + "/one.json", dir).code, 0);
    ASSERT_EQ(uvr(render + dir + "/four.png --supersample 4 --stats " + dir +
                      "/four.json --heatmap " + dir + "/h.png",
                  dir)
                  .code,
              0);
    const auto one = readJson(dir + "/one.json"), four = readJson(dir + "/four.json");
    EXPECT_EQ(one["supersample"], 1);
    EXPECT_EQ(one["rays"], 24 * 16);
    EXPECT_EQ(four["supersample"], 4);
    EXPECT_EQ(four["jitter"], false);
    EXPECT_EQ(four["rays"], 24 * 16 * 16);
    // Per pixel: the sum over its 16 rays; per ray about the same as with one ray.
    EXPECT_NEAR(four["mean_samples_per_pixel"].get<double>(),
                16.0 * four["mean_samples_per_ray"].get<double>(), 1e-6);
    EXPECT_NEAR(four["mean_samples_per_ray"].get<double>(),
                one["mean_samples_per_ray"].get<double>(),
                0.2 * one["mean_samples_per_ray"].get<double>());
    ASSERT_EQ(
        uvr(render + dir + "/j.png --supersample 2 --jitter --stats " + dir + "/j.json", dir).code,
        0);
    EXPECT_EQ(readJson(dir + "/j.json")["jitter"], true);
    // Out of range, or --jitter without rays to move: one line.
    for (const char* n : {"0", "9", "-2"})
        expectOneLineError(uvr(render + dir + "/x.png --supersample " + n, dir),
                           {std::string("--supersample ") + n, "expected an integer in [1, 8]"}, n);
    expectOneLineError(uvr(render + dir + "/x.png --jitter", dir),
                       {"--jitter", "--supersample 2 or more"}, "jitter alone");
    // Every flag has its help.
    const CliRun help = uvr("render --help", dir);
    for (const char* flag : {"--parallel", "--parallel-scale", "--supersample", "--jitter"})
        EXPECT_NE(help.out.find(flag), std::string::npos) << flag;
}

}  // namespace
}  // namespace uvr

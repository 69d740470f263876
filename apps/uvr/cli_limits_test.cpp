// SPDX-License-Identifier: MIT
// End-to-end tests of the CLI's bounds on memory and time: --max-memory over a whole load and the
// other large allocations, the cap on a frame's samples, many fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;

/// A unit cube of 5 tetrahedra with the point field x, as a legacy ASCII file.
std::string writeCube(const std::string& path) {
    return testing::writeFile(path,
                              "# vtk DataFile Version 3.0\ncube\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                              "POINTS 8 float\n0 0 0 1 0 0 0 1 0 1 1 0 0 0 1 1 0 1 0 1 1 1 1 1\n"
                              "CELLS 5 25\n4 0 1 2 4\n4 1 3 2 7\n4 1 4 5 7\n4 2 4 6 7\n4 1 2 4 7\n"
                              "CELL_TYPES 5\n10 10 10 10 10\nPOINT_DATA 8\nSCALARS x float 1\n"
                              "LOOKUP_TABLE default\n0 1 0 1 0 1 0 1\n");
}

TEST(CliLimits, ImageBuffersAboveMaxMemoryAreRefusedBeforeLoading) {
    const std::string dir = testing::scratchDir();
    const std::string cube = writeCube(dir + "/cube.vtk");
    expectOneLineError(
        uvr("-q render " + cube + " -o out.png --size 16384x16384 --max-memory 100M", dir),
        {"--size 16384x16384: the image buffers (24 bytes per pixel) would need about "
         "6442450944 bytes, more than the --max-memory limit of 104857600 bytes"});
    expectOneLineError(
        uvr("-q render " + cube + " -o out.png --size 2048x2048 --heatmap h.png --max-memory 100M",
            dir),
        {"--size 2048x2048: the image buffers (24 bytes per pixel, 20 more for the --heatmap)"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.png"));
    EXPECT_EQ(uvr("-q render " + cube + " -o out.png --size 64x64 --max-memory 100M", dir).code, 0);
}

TEST(CliLimits, LargeFramesNeedAnExplicitMemoryLimit) {
    // The 16384x16384 of five tetrahedra took 5.3 GB and a minute under the default
    // limit (80% of physical memory); without an explicit --max-memory a command's image
    // buffers must fit 2 GiB (kDefaultFrameMemoryBytes), for every command that renders.
    const std::string dir = testing::scratchDir();
    const std::string cube = writeCube(dir + "/cube.vtk");
    const std::string limit =
        "more than the default limit of image buffers, 2147483648 bytes (2 GiB): give "
        "--max-memory to allow a larger frame (e.g. --max-memory 7G)";
    expectOneLineError(uvr("-q render " + cube + " -o out.png --size 16384x16384", dir),
                       {"--size 16384x16384: the image buffers (24 bytes per pixel) would need "
                        "about 6442450944 bytes, " +
                        limit},
                       "render");
    expectOneLineError(uvr("-q animate " + cube + " -o frames --size 16384x16384", dir), {limit},
                       "animate");
    expectOneLineError(uvr("-q demo -o out.png --size 16384x16384 --cells 1000", dir), {limit},
                       "demo");
    expectOneLineError(uvr("-q bench " + cube + " --size 8192x8192", dir),
                       {"--size 8192x8192: the frames of", "more than the default limit"},
                       "bench: its frames together");
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.png"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/frames"));
    // An explicit limit allows it (a junk mesh then fails to read: the frame passed).
    const std::string junk = testing::writeFile(dir + "/junk.vtk", "not a mesh\n");
    const CliRun r =
        uvr("-q render " + junk + " -o out.png --size 16384x16384 --max-memory 7G", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err.find("image buffers"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("junk.vtk"), std::string::npos) << r.err;
    // 8192x8192 (1.5 GiB) needs no flag.
    const CliRun ok = uvr("-q render " + junk + " -o out.png --size 8192x8192", dir);
    EXPECT_EQ(ok.err.find("image buffers"), std::string::npos) << ok.err;
}

TEST(CliLimits, GeneratedMeshesAboveMaxMemoryAreRefusedBeforeGenerating) {
    const std::string dir = testing::scratchDir();
    // A .vtu is built whole first; a .uvrm is written slab by slab (the slabs must fit).
    expectOneLineError(uvr("-q generate --cells 4000000000 -o g.vtu --max-memory 1G", dir),
                       {"--cells 4000000000: the mesh of ", " tetrahedra would need about ",
                        "more than the --max-memory limit of 1073741824 bytes"});
    expectOneLineError(uvr("-q generate --cells 4000000000 -o g.uvrm --max-memory 10M", dir),
                       {"--cells 4000000000: the slabs of ", " tetrahedra would need about ",
                        "more than the --max-memory limit of 10485760 bytes"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/g.vtu"));
    expectOneLineError(uvr("-q demo --cells 2000000000 -o d.png --max-memory 1G", dir),
                       {"--cells 2000000000 --size 1024x1024: generating, preparing and rendering",
                        "more than the --max-memory limit of 1073741824 bytes"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/g.uvrm"));
    EXPECT_FALSE(std::filesystem::exists(dir + "/d.png"));
    EXPECT_EQ(uvr("-q generate --cells 1000 -o g.uvrm --max-memory 1M", dir).code, 0);
}

TEST(CliLimits, AbsurdStepIsRefusedWithTheEstimateAndAStepThatWorks) {
    // 3e-6 over a unit cube is 577,000 samples per ray: 64x64 pixels would take minutes.
    const std::string dir = testing::scratchDir();
    const std::string cube = writeCube(dir + "/cube.vtk");
    expectOneLineError(
        uvr("-q render " + cube + " -o out.png --size 64x64 --sample-distance 3e-6", dir),
        {"--sample-distance 3e-06 would take up to 2.36e+09 samples (64x64 pixels x 5.77e+05 per "
         "ray across the bounds' diagonal 1.73), more than the 100,000 samples per ray "
         "allowed: use --sample-distance 1.8e-05 or larger (the default here is "});
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.png"));
    EXPECT_EQ(
        uvr("-q render " + cube + " -o out.png --size 64x64 --sample-distance 1.8e-5", dir).code,
        0);
}

TEST(CliLimits, MaxMemoryBoundsTheWholeLoad) {
    // 60 point fields of 10,000 values: each 40 KB array fits 1M, the 2.4 MB load does not.
    const std::string dir = testing::scratchDir();
    std::string text =
        "# vtk DataFile Version 3.0\nfields\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 10000 "
        "float\n" +
        std::string(120000, '\0') + "\nPOINT_DATA 10000\n";
    for (int f = 0; f < 60; ++f)
        text += "SCALARS f" + std::to_string(f) + " float 1\nLOOKUP_TABLE default\n" +
                std::string(40000, '\0') + "\n";
    const std::string path = testing::writeFile(dir + "/fields.vtk", text);
    expectOneLineError(uvr("-q info " + path + " --max-memory 3M", dir),
                       {path + ": tuples of SCALARS 'f", "needs 40000 bytes, which with the ",
                        "exceed the memory limit of 3145728 bytes (--max-memory)"});
    EXPECT_EQ(uvr("-q info " + path + " --max-memory 6M", dir).code, 0);
}

TEST(CliLimits, InfoOnFiftyThousandFieldsIsLinear) {
    // Looking each field up by name made `info` quadratic: minutes for 200,000 fields.
    const std::string dir = testing::scratchDir();
    std::string text =
        "# vtk DataFile Version 3.0\nfields\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n"
        "0 0 0\nPOINT_DATA 1\nFIELD FieldData 50000\n";
    for (int f = 0; f < 50000; ++f) text += "f" + std::to_string(f) + " 1 1 float\n1\n";
    const std::string path = testing::writeFile(dir + "/many.vtk", text);
    const CliRun r = uvr("-q info " + path, dir);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("f49999 "), std::string::npos);
}

}  // namespace
}  // namespace uvr

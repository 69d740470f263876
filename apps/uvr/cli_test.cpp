// SPDX-License-Identifier: MIT
// End-to-end tests of the uvr command-line tool: exit codes, messages, outputs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_test_support.h"
#include "parse_errors.h"
#include "test_support.h"
#include "uvr/core/text.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/render/depth_image.h"
#include "uvr/render/image.h"
#include "uvr/render/image_metrics.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;
using ::testing::HasSubstr;
using ::testing::Not;

TEST(Cli, HelpListsEverySubcommand) {
    const std::string dir = testing::scratchDir();
    const CliRun r = uvr("--help", dir);
    EXPECT_EQ(r.code, 0);
    for (const char* cmd :
         {"info", "render", "demo", "convert", "generate", "refine", "compare", "bench", "presets"})
        EXPECT_NE(r.out.find(cmd), std::string::npos) << cmd;
    const CliRun rh = uvr("render --help", dir);
    EXPECT_EQ(rh.code, 0);
    EXPECT_NE(rh.out.find("--opacity"), std::string::npos);
}

TEST(Cli, BadFlagsExitWithCode2AndOneLine) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx = testing::sharedData("spx.vtk");
    const std::string out = dir + "/o.png";
    for (const std::string& args : std::vector<std::string>{
             "render " + spx + " -o " + out + " --size 0x10",
             "render " + spx + " -o " + out + " --size 100000x100000",
             "render " + spx + " -o " + out + " --sample-distance -1",
             "render " + spx + " -o " + out + " --sample-distance nan",
             "render " + spx + " -o " + out + " --range 5,1",
             "render " + spx + " -o " + out + " --camera-position nan,0,0",
             "render " + spx + " -o " + out + " --field nosuch",
             "render " + spx + " -o " + out + " --tf nosuch",
             "render " + spx + " -o " + out + " --opacity zigzag",
             "render " + spx + " -o " + out + " --build-device gpu",
             "render " + spx + " -o " + dir + "/missing/o.png",
             "render " + spx + " --bogus -o " + out, "render " + spx, "frobnicate"}) {
        const CliRun r = uvr("-q " + args, dir);
        EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
        EXPECT_EQ(testing::lineCount(r.err), 1) << args << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("uvr: error: ", 0), 0u) << r.err;
        EXPECT_FALSE(std::filesystem::exists(out)) << args;
    }
}

TEST(Cli, GpuBuildRendersTheSameImageOrIsRefusedClearly) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx = testing::sharedData("spx.vtk");
    for (const char* method : {"reference", "adaptive"}) {
        const std::string args = "-q render " + spx + " --device cpu --method " + method +
                                 " --size 64x48 --opacity 0:0,1:0.5 -o ";
        const CliRun cpu = uvr(args + dir + "/cpu.png --build-device cpu", dir);
        ASSERT_EQ(cpu.code, 0) << cpu.err;
        const CliRun gpu = uvr(args + dir + "/gpu.png --build-device cuda", dir);
        if (!cudaDeviceAvailable()) {
            EXPECT_NE(gpu.code, 0);
            EXPECT_EQ(testing::lineCount(gpu.err), 1) << gpu.err;
            EXPECT_NE(gpu.err.find("CUDA"), std::string::npos) << gpu.err;
            EXPECT_FALSE(std::filesystem::exists(dir + "/gpu.png"));
            continue;
        }
        ASSERT_EQ(gpu.code, 0) << gpu.err;
        const CliRun cmp =
            uvr("compare " + dir + "/cpu.png " + dir + "/gpu.png --min-ssim 0.99", dir);
        EXPECT_EQ(cmp.code, 0) << method << ": " << cmp.out << cmp.err;
    }
}

TEST(Cli, BadFilesExitWithCode2NamingTheFile) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    // A binary file cut in half.
    std::ifstream in(testing::sharedData("post.vtk"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    testing::writeFile(dir + "/cut.vtk", bytes.substr(0, bytes.size() / 2));
    for (const std::string& file : {dir + "/cut.vtk", dir + "/absent.vtk"}) {
        const CliRun r = uvr("-q render " + file + " -o " + dir + "/o.png", dir);
        EXPECT_EQ(r.code, 2) << r.err;
        EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
        EXPECT_EQ(testing::lineCount(r.err), 1) << r.err;
    }
    EXPECT_FALSE(std::filesystem::exists(dir + "/o.png"));
}

TEST(Cli, MaxMemoryRefusesLargerArraysBeforeAllocating) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string post = testing::sharedData("post_tets.vtk");
    CliRun r = uvr("-q info " + post + " --max-memory 1M", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("exceed the memory limit of 1048576 bytes"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(post), std::string::npos);
    EXPECT_EQ(uvr("-q info " + post + " --max-memory 1G", dir).code, 0);
    r = uvr("-q info " + post + " --max-memory 12Q", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(testing::lineCount(r.err), 1) << r.err;
}

TEST(Cli, InfoAndRenderOnEveryRealFile) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::map<std::string, std::pair<int, int>> counts = {
        {"spx.vtk", {2896, 12936}},          {"post.vtk", {2288, 8750}},
        {"tetraMesh.vtk", {55, 160}},        {"bluntfin_tets.vtk", {40960, 187395}},
        {"post_tets.vtk", {109744, 513375}}, {"cylinder_quadratic_as_tets.vtk", {465, 1522}},
        {"hexa.vtk", {12167, 10648}},        {"fire_ug.vtu", {12323, 10462}}};
    for (const auto& [name, pc] : counts) {
        const CliRun r = uvr("-q info --json " + testing::sharedData(name), dir);
        ASSERT_EQ(r.code, 0) << name << r.err;
        const auto j = nlohmann::json::parse(r.out);
        EXPECT_EQ(j["points"], pc.first) << name;
        EXPECT_EQ(j["cells"], pc.second) << name;
        EXPECT_FALSE(j["fields"].empty()) << name;
        const CliRun text = uvr("-q info " + testing::sharedData(name), dir);
        EXPECT_EQ(text.code, 0);
        EXPECT_NE(text.out.find("validation:"), std::string::npos);
        // Every real file renders, and covers part (not all) of the image.
        const std::string png = dir + "/" + name + ".png";
        const CliRun render = uvr("-q render " + testing::sharedData(name) + " -o " + png +
                                      " --size 24x24 --opacity constant:0.5",
                                  dir);
        ASSERT_EQ(render.code, 0) << name << render.err;
        const Image img = readPng(png);
        const auto covered = std::count_if(img.pixels.begin(), img.pixels.end(),
                                           [](const Vec4f& p) { return p.w > 0.f; });
        EXPECT_GT(covered, 8) << name;
        EXPECT_LT(covered, 24 * 24) << name;
    }
}

TEST(Cli, RenderWritesPngAndStats) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const CliRun r = uvr("-q render " + testing::sharedData("spx.vtk") + " -o " + dir +
                             "/spx.png --size 64x48 --stats " + dir + "/s.json --tf viridis",
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const Image img = readPng(dir + "/spx.png");
    EXPECT_EQ(img.width, 64);
    EXPECT_EQ(img.height, 48);
    EXPECT_GT(img.at(32, 24).w, 0.f);  // the mesh covers the centre
    EXPECT_EQ(img.at(0, 0).w, 0.f);    // and not the corner
    std::ifstream in(dir + "/s.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_GT(j["samples"].get<double>(), 0);
    EXPECT_EQ(j["image"]["width"], 64);
    EXPECT_EQ(j["mesh"]["cells"], 12936);
    EXPECT_GT(j["render_seconds"].get<double>(), 0);
}

TEST(Cli, StepRuleQualityAndSamplingFlags) {
    // The defaults pre-integrate and use the error rule; the paper's point samples and variance
    // rule are there for comparison; every bad combination gets its one-line error.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx = testing::sharedData("spx.vtk") + " --size 48x48 ";
    const std::string two = " --opacity 0:0,0.3:0,0.32:0.8,0.34:0,0.6:0,0.62:0.8,0.64:0,1:0";
    ASSERT_EQ(uvr("-q render " + spx + two + " --method exact -o e.png", dir).code, 0);
    const auto ssimOf = [&](const std::string& flags) {
        const CliRun r = uvr("-q render " + spx + two + flags + " -o x.png --stats s.json", dir);
        EXPECT_EQ(r.code, 0) << flags << ": " << r.err;
        return compareImages(toRgb8(readPng(dir + "/e.png")), toRgb8(readPng(dir + "/x.png"))).ssim;
    };
    EXPECT_GE(ssimOf(" --method adaptive --quality 0.99"), 0.98);
    std::ifstream stats(dir + "/s.json");
    const auto j = nlohmann::json::parse(stats);
    EXPECT_EQ(j["step_rule"], "error");
    EXPECT_EQ(j["sampling"], "preintegrated");
    EXPECT_FLOAT_EQ(j["quality"].get<float>(), 0.99f);
    EXPECT_GE(ssimOf(" --method reference"), 0.98);
    EXPECT_LT(ssimOf(" --method adaptive --step-rule variance --power 2 --sampling point"), 0.98);
    const std::pair<const char*, const char*> bad[] = {
        {" --method adaptive --quality 1", "--quality"},
        {" --method adaptive --quality 0.2", "--quality"},
        {" --method reference --quality 0.9", "--quality is not read by --method reference"},
        {" --method adaptive --step-rule variance --quality 0.9", "--step-rule error"},
        {" --method adaptive --power 3", "--step-rule variance"},
        {" --method adaptive --step-rule fastest", "--step-rule"},
        {" --method exact --sampling point",
         "--sampling is not read by --method exact: it needs --method reference or adaptive"},
        {" --sampling linear", "--sampling"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr("-q render " + spx + flags + " -o y.png", dir), {says}, flags);
    EXPECT_FALSE(std::filesystem::exists(dir + "/y.png"));
}

TEST(Cli, OpacityLawFlag) {
    // --opacity-law picks how opacity absorbs (default attenuation, in the stats); a slab of
    // constant opacity 1 per unit is translucent under attenuation and opaque under
    // transmittance.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx =
        testing::sharedData("spx.vtk") + " --size 48x48 --opacity constant:1 --opacity-unit 1e6";
    std::string law[2];
    int i = 0;
    for (const char* flags : {"", " --opacity-law transmittance"}) {
        const CliRun r = uvr("-q render " + spx + flags + " -o l.png --stats s.json", dir);
        ASSERT_EQ(r.code, 0) << flags << ": " << r.err;
        std::ifstream stats(dir + "/s.json");
        law[i] = nlohmann::json::parse(stats)["opacity_law"].get<std::string>();
        const Image img = readPng(dir + "/l.png");
        // The centre's ray crosses far less than the 1e6 opacity unit.
        if (i++ == 0)
            EXPECT_LT(img.at(24, 24).w, 0.01f);
        else
            EXPECT_EQ(img.at(24, 24).w, 1.f);
    }
    EXPECT_EQ(law[0], "attenuation");
    EXPECT_EQ(law[1], "transmittance");
    expectOneLineError(uvr("-q render " + spx + " --opacity-law linear -o y.png", dir),
                       {"--opacity-law"}, "linear");
    EXPECT_FALSE(std::filesystem::exists(dir + "/y.png"));
}

TEST(Cli, ExactMethodAgreesWithTheReferenceAtASixteenthOfItsStep) {
    // The Oxygen Post has seams of unshared faces (its O-grid): rays that cross them are located
    // again, never dropped, so exact equals the converged fixed-step image.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string post = testing::sharedData("post_tets.vtk");
    const std::string view =
        " --size 96x96 --azimuth -30 --elevation 25 --opacity 0:0,0.3:0.6,0.35:0,0.7:0.8,1:0.2 ";
    const CliRun e = uvr("-q render " + post + " --method exact -o e.png" + view, dir);
    ASSERT_EQ(e.code, 0) << e.err;
    const CliRun f = uvr(
        "-q render " + post + " --method reference --sample-distance 0.00587 -o f.png" + view, dir);
    ASSERT_EQ(f.code, 0) << f.err;
    const ImageComparison m =
        compareImages(toRgb8(readPng(dir + "/e.png")), toRgb8(readPng(dir + "/f.png")));
    EXPECT_GE(m.ssim, 0.999);
    expectOneLineError(
        uvr("-q render " + post + " --method exact --max-sample-distance 1 -o x.png", dir),
        {"--max-sample-distance is not read by --method exact: it needs --method adaptive"},
        "exact with --max-sample-distance");
    // 0 means nothing: refused, not taken as the default.
    for (const char* flag : {"--sample-distance", "--opacity-unit", "--max-sample-distance"})
        expectOneLineError(uvr("-q render " + post + " " + flag + " 0 -o x.png", dir), {flag},
                           std::string(flag) + " 0");
}

TEST(Cli, ConvertedMeshRendersIdentically) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string src = testing::sharedData("bluntfin_tets.vtk");
    ASSERT_EQ(uvr("-q convert " + src + " " + dir + "/b.uvrm", dir).code, 0);
    const std::string common = " --size 48x48 --field speed --background 0,0,0";
    ASSERT_EQ(uvr("-q render " + src + " -o " + dir + "/a.png" + common, dir).code, 0);
    ASSERT_EQ(uvr("-q render " + dir + "/b.uvrm -o " + dir + "/b.png" + common, dir).code, 0);
    const Image a = readPng(dir + "/a.png"), b = readPng(dir + "/b.png");
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    for (size_t i = 0; i < a.pixels.size(); ++i) ASSERT_EQ(a.pixels[i].x, b.pixels[i].x);
}

TEST(Cli, GenerateAndDemo) {
    const std::string dir = testing::scratchDir();
    CliRun r = uvr("-q generate shell --cells 2000 -o " + dir + "/s.uvrm", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q info --json " + dir + "/s.uvrm", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_GT(nlohmann::json::parse(r.out)["cells"].get<int>(), 1000);
    EXPECT_EQ(uvr("-q generate cube -o " + dir + "/c.uvrm", dir).code, 2);
    r = uvr("-q demo --cells 5000 --size 32x32 -o " + dir + "/demo.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(readPng(dir + "/demo.png").width, 32);
}

TEST(Cli, RenderNamesEveryPreparationPhaseInALog) {
    // stderr is a file: phases print their start lines; phases under a second print no end line.
    const std::string dir = testing::scratchDir();
    CliRun r = uvr("-q generate shell --cells 5000 -o " + dir + "/s.uvrm", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("render " + dir + "/s.uvrm --size 32x32 -o " + dir + "/s.png --method adaptive", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    std::size_t at = 0;
    for (const char* line :
         {"uvr: checking ", "uvr: preparing ", "uvr: finding face neighbours\n",
          "uvr: building k-d partitions (up to ", "uvr: building the cell tree\n",
          "uvr: building seed grids\n", "uvr: measuring the partitions' gradient spreads\n",
          "uvr: looking for NaN values\n", "uvr: building macrocell grids\n"}) {
        const std::size_t found = r.err.find(line, at);
        ASSERT_NE(found, std::string::npos) << "no '" << line << "' (in order) in\n" << r.err;
        EXPECT_EQ(r.err.find(line, found + 1), std::string::npos) << line << " twice:\n" << r.err;
        at = found;
    }
    EXPECT_EQ(r.err.find(": done ("), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
    // The default (auto) builds only what its pick renders with, and says why it picked it.
    r = uvr("render " + dir + "/s.uvrm --size 32x32 -o " + dir + "/s.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, HasSubstr("uvr: building the BVH over 6084 cells\n"));
    EXPECT_THAT(r.err, Not(HasSubstr("k-d partitions")));
    EXPECT_THAT(r.err,
                HasSubstr("uvr: auto: exact (about 12 cells per ray, at most 32 on the CPU)"));
}

TEST(Cli, GenerateMixedCells) {
    const std::string dir = testing::scratchDir();
    // 4^3 blocks (about 4.2 cells a block), every cell type, nothing for validation to report.
    CliRun r = uvr("-q generate mixed --cells 270 --seed 3 -o " + dir + "/m.vtu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q info --json " + dir + "/m.vtu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_GT(j["cells"].get<int>(), 200);
    EXPECT_LT(j["cells"].get<int>(), 400);
    EXPECT_TRUE(j["validation"].empty()) << j["validation"];
    const std::string text = j.dump();
    for (const char* name :
         {"hexahedron", "wedge", "pyramid", "tetra", "linear", "xyz", "block", "cell_type"})
        EXPECT_NE(text.find(name), std::string::npos) << name << " not in " << text;
    // Too much jitter for its cells, and options it does not take.
    r = uvr("-q generate mixed --jitter 0.2 -o " + dir + "/x.vtu", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("jitter must be in [0, 0.15"), std::string::npos) << r.err;
    r = uvr("-q generate mixed --fields linear -o " + dir + "/x.vtu", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--fields and --steps do not apply"), std::string::npos) << r.err;
    EXPECT_FALSE(std::ifstream(dir + "/x.vtu").good());
}

TEST(Cli, HexahedraRenderNativelyUnlessSplit) {
    const std::string dir = testing::scratchDir();
    CliRun r = uvr("-q generate hex --cells 1000 --seed 2 -o " + dir + "/h.vtu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    for (const bool split : {false, true}) {
        const std::string tag = split ? "split" : "native";
        r = uvr("render " + dir + "/h.vtu --field xyz --size 48x48 --device cpu -o " + dir + "/" +
                    tag + ".png --stats " + dir + "/" + tag + ".json" +
                    (split ? " --split-cells" : ""),
                dir);
        ASSERT_EQ(r.code, 0) << r.err;
        std::ifstream in(dir + "/" + tag + ".json");
        const auto j = nlohmann::json::parse(in);
        EXPECT_EQ(j["mesh"]["cells"].get<int>(), 1000) << tag;
        EXPECT_EQ(j["mesh"]["hexahedra"].get<int>(), split ? 0 : 1000) << tag;
        EXPECT_EQ(j["mesh"]["tetrahedra"].get<int>(), split ? 6000 : 0) << tag;
        EXPECT_NE(r.err.find(split ? "prepared 6000 tetrahedra" : "(1000 hexahedra)"),
                  std::string::npos)
            << r.err;
    }
}

TEST(Cli, RefineMultipliesTetrahedraBy8PerLevel) {
    const std::string dir = testing::scratchDir();
    CliRun r = uvr("-q generate box --cells 1000 --fields linear -o " + dir + "/b.uvrm", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q info --json " + dir + "/b.uvrm", dir);
    const auto cells = nlohmann::json::parse(r.out)["cells"].get<std::uint64_t>();
    r = uvr("-q refine " + dir + "/b.uvrm " + dir + "/r.vtu --levels 2", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q info --json " + dir + "/r.vtu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["cells"].get<std::uint64_t>(), 64 * cells);
    EXPECT_TRUE(j["validation"].empty()) << j["validation"];
    // Bad levels and unwritable outputs fail cleanly and leave no file behind.
    EXPECT_EQ(uvr("-q refine " + dir + "/b.uvrm " + dir + "/x.uvrm --levels 99", dir).code, 2);
    EXPECT_EQ(uvr("-q refine " + dir + "/b.uvrm " + dir + "/x.png", dir).code, 2);
    r = uvr("-q --max-memory 1M refine " + dir + "/b.uvrm " + dir + "/x.uvrm --levels 3", dir);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("--max-memory"), std::string::npos) << r.err;
    EXPECT_FALSE(std::ifstream(dir + "/x.uvrm").good());
}

TEST(Cli, AdaptiveRenderWithHeatmapAndStats) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const CliRun r = uvr("-q render " + testing::sharedData("bluntfin_tets.vtk") + " -o " + dir +
                             "/a.png --size 64x48 --method adaptive --opacity step:0.5 "
                             "--leaf-cells 512 --heatmap " +
                             dir + "/h.png --stats " + dir + "/s.json",
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    std::ifstream in(dir + "/s.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["method"], "adaptive");
    EXPECT_GT(j["partitions"]["count"].get<int>(), 100);
    EXPECT_GE(j["partitions"]["duplication_factor"].get<double>(), 1.0);
    EXPECT_LE(j["partitions"]["cells_median"].get<int>(), 512);
    EXPECT_GT(j["partitions_skipped"].get<double>(), 0);  // the step TF hides half the range
    EXPECT_GE(j["tf_update_seconds"].get<double>(), 0);
    const Image h = readPng(dir + "/h.png");
    EXPECT_EQ(h.height, 48);
    EXPECT_GT(h.width, 64);  // the colour bar and its scale
    // Method-only flags with another method are refused.
    EXPECT_EQ(uvr("-q render " + testing::sharedData("spx.vtk") + " -o " + dir +
                      "/b.png --method reference --no-skip",
                  dir)
                  .code,
              2);
    // The default is auto (issue 29): on SPX's 12,936 tetrahedra a ray crosses few cells, so it
    // renders exact (faster there, and the truth); a flag tuning sampling makes it adaptive.
    const auto statsOf = [&](const char* mesh, const std::string& flags) {
        const CliRun run = uvr("-q render " + testing::sharedData(mesh) + " -o " + dir +
                                   "/c.png --size 32x32 --stats " + dir + "/c.json " + flags,
                               dir);
        EXPECT_EQ(run.code, 0) << flags << ": " << run.err;
        std::ifstream file(dir + "/c.json");
        return run.code == 0 ? nlohmann::json::parse(file) : nlohmann::json::object();
    };
    const auto d = statsOf("spx.vtk", "");
    EXPECT_EQ(d.value("method", ""), "exact");
    EXPECT_EQ(d.value("method_asked", ""), "auto");
    EXPECT_THAT(d.value("method_reason", ""),
                HasSubstr("auto: exact (about 13.2 cells per ray, at most 32 on the CPU)"));
    EXPECT_FALSE(d.contains("partitions"));  // only what exact needs was prepared
    for (const char* tuning :
         {"--quality 0.995", "--sample-distance 0.05", "--sampling point", "--no-skip"}) {
        const auto t = statsOf("spx.vtk", tuning);
        EXPECT_EQ(t.value("method", ""), "adaptive") << tuning;
        EXPECT_TRUE(t.contains("partitions")) << tuning;
    }
    // Many cells per ray: adaptive (Blunt Fin, 187,395 tetrahedra: about 70).
    const auto b = statsOf("bluntfin_tets.vtk", "");
    EXPECT_EQ(b.value("method", ""), "adaptive");
    EXPECT_THAT(b.value("method_reason", ""), HasSubstr("more than 32 on the CPU"));
}

TEST(Cli, ClipPlanesAndBoxCutTheVolumeAndAreReported) {
    // Issue 32: --clip-plane (repeatable) and --clip-box, in the file's coordinates; the stats
    // report them as given; the kept part of Blunt Fin is less than the whole, and a box around
    // the whole mesh changes nothing.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string fin = "-q render " + testing::sharedData("bluntfin_tets.vtk") +
                            " --size 48x32 --method exact --azimuth 30 --elevation 20 ";
    ASSERT_EQ(uvr(fin + "-o whole.png", dir).code, 0);
    const CliRun cut = uvr(fin +
                               "-o cut.png --clip-plane 3,0,0,1,0,0 --clip-plane 0,4,0,0,-1,0 "
                               "--stats s.json",
                           dir);
    ASSERT_EQ(cut.code, 0) << cut.err;
    std::ifstream in(dir + "/s.json");
    const auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j["clip_planes"].size(), 2u);
    EXPECT_EQ(j["clip_planes"][1], nlohmann::json::parse("[0,4,0,0,-1,0]"));
    EXPECT_FALSE(j.contains("clip_box"));
    EXPECT_FALSE(j.contains("clip_surface"));
    // --clip-surface: the cut face drawn and reported, with the coefficients that light it.
    const CliRun face = uvr(fin +
                                "-o face.png --clip-plane 3,0,0,1,0,0 --clip-plane 0,4,0,0,-1,0 "
                                "--clip-surface --ambient 0.3 --stats f.json",
                            dir);
    ASSERT_EQ(face.code, 0) << face.err;
    std::ifstream fin2(dir + "/f.json");
    const auto f = nlohmann::json::parse(fin2);
    EXPECT_EQ(f.value("clip_surface", false), true);
    EXPECT_FLOAT_EQ(f.value("ambient", 0.f), 0.3f);
    EXPECT_LT(
        compareImages(toRgb8(readPng(dir + "/cut.png")), toRgb8(readPng(dir + "/face.png"))).ssim,
        0.99);
    const Image whole = readPng(dir + "/whole.png"), part = readPng(dir + "/cut.png");
    double sumWhole = 0.0, sumPart = 0.0;
    for (std::size_t i = 0; i < whole.pixels.size(); ++i)
        sumWhole += whole.pixels[i].w, sumPart += part.pixels[i].w;
    EXPECT_LT(sumPart, 0.8 * sumWhole);
    EXPECT_GT(sumPart, 0.05 * sumWhole);
    // Before the mesh file too: each --clip-plane takes one value.
    const CliRun before = uvr("-q render --clip-plane 3,0,0,1,0,0 --clip-plane 0,4,0,0,-1,0 " +
                                  testing::sharedData("bluntfin_tets.vtk") +
                                  " --size 48x32 --method exact --azimuth 30 --elevation 20 "
                                  "-o before.png",
                              dir);
    ASSERT_EQ(before.code, 0) << before.err;
    ASSERT_EQ(uvr(fin + "-o boxed.png --clip-box -100,-100,-100,100,100,100", dir).code, 0);
    const ImageComparison same = compareImages(toRgb8(whole), toRgb8(readPng(dir + "/boxed.png")));
    EXPECT_GE(same.ssim, 0.9999);
    const std::pair<const char*, const char*> bad[] = {
        {"--clip-plane 1,2,3", "--clip-plane '1,2,3': expected ox,oy,oz,nx,ny,nz"},
        {"--clip-plane 0,0,0,0,0,0", "normal other than 0,0,0"},
        {"--clip-surface", "read only with clip planes or a clip box"},
        {"--clip-box 1,1,1,0,0,0", "x0 <= x1"},
        {"--clip-box 0,0,0,1,1,nan", "--clip-box"},
        {"--clip-plane 0,0,0,1,0,0 --clip-plane 0,0,0,1,0,0 --clip-plane 0,0,0,1,0,0 "
         "--clip-plane 0,0,0,1,0,0 --clip-plane 0,0,0,1,0,0 --clip-plane 0,0,0,1,0,0 "
         "--clip-plane 0,0,0,1,0,0",
         "at most 6"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr(fin + "-o x.png " + flags, dir), {says}, flags);
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(Cli, ShadeLightsTheVolumeAndIsReported) {
    // Issue 32: --shade with ParaView's coefficients; the stats report them; a coefficient
    // without --shade, or out of range, is refused in one line.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string fin = "-q render " + testing::sharedData("bluntfin_tets.vtk") +
                            " --size 48x32 --method exact --azimuth 30 --elevation 20 ";
    ASSERT_EQ(uvr(fin + "-o flat.png --stats flat.json", dir).code, 0);
    const CliRun lit = uvr(fin +
                               "-o lit.png --shade --ambient 0.2 --diffuse 0.7 --specular 0.1 "
                               "--specular-power 20 --stats lit.json",
                           dir);
    ASSERT_EQ(lit.code, 0) << lit.err;
    std::ifstream flatIn(dir + "/flat.json"), litIn(dir + "/lit.json");
    const auto flat = nlohmann::json::parse(flatIn), j = nlohmann::json::parse(litIn);
    EXPECT_EQ(flat["shade"], false);
    EXPECT_FALSE(flat.contains("ambient"));
    EXPECT_EQ(j["shade"], true);
    EXPECT_FLOAT_EQ(j["ambient"].get<float>(), 0.2f);
    EXPECT_FLOAT_EQ(j["diffuse"].get<float>(), 0.7f);
    EXPECT_FLOAT_EQ(j["specular"].get<float>(), 0.1f);
    EXPECT_FLOAT_EQ(j["specular_power"].get<float>(), 20.f);
    // The light only dims or brightens the colours: the same opacity, other colours.
    const Image a = readPng(dir + "/flat.png"), b = readPng(dir + "/lit.png");
    double alphaDiff = 0.0, colourDiff = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        alphaDiff = std::max(alphaDiff, double(std::fabs(a.pixels[i].w - b.pixels[i].w)));
        colourDiff += std::fabs(a.pixels[i].x - b.pixels[i].x);
    }
    EXPECT_LE(alphaDiff, 1.5 / 255.0);
    EXPECT_GT(colourDiff / double(a.pixels.size()), 0.005);
    const std::pair<const char*, const char*> bad[] = {
        {"--ambient 0.3", "--ambient 0.3: read only with --shade on or an --iso surface"},
        {"--specular-power 8", "--specular-power 8: read only with --shade on or an --iso surface"},
        {"--shade --diffuse 1.5", "--diffuse 1.5: expected a number in [0, 1]"},
        {"--shade --specular-power 200", "--specular-power 200: expected a number in [0, 128]"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr(fin + "-o x.png " + flags, dir), {says}, flags);
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(Cli, GradientOpacityScalesTheOpacityAndIsReported) {
    // Issue 32: --gradient-opacity scales the opacity by the gradient's magnitude (a constant
    // function here: 1 changes no pixel, 0 hides everything, 0.5 lies between); the stats give
    // it as written; --normals is read with it; bad ones are refused in one line, and cell data
    // has no gradient.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string fin = "-q render " + testing::sharedData("bluntfin_tets.vtk") +
                            " --size 48x32 --method exact --azimuth 30 --elevation 20 ";
    ASSERT_EQ(uvr(fin + "-o plain.png", dir).code, 0);
    for (const auto& [name, f] : {std::pair{"one", "0:1"}, {"zero", "0:0"}, {"half", "0:0.5"}}) {
        const CliRun r = uvr(
            fin + "-o " + name + ".png --gradient-opacity " + f + " --normals cell --stats s.json",
            dir);
        ASSERT_EQ(r.code, 0) << r.err;
    }
    std::ifstream in(dir + "/s.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["gradient_opacity"], "0:0.5");
    EXPECT_EQ(j["normals"], "cell");
    EXPECT_EQ(j["shade"], false);
    const Image plain = readPng(dir + "/plain.png"), one = readPng(dir + "/one.png"),
                zero = readPng(dir + "/zero.png"), half = readPng(dir + "/half.png");
    double sumPlain = 0.0, sumHalf = 0.0, sumZero = 0.0;
    for (std::size_t i = 0; i < plain.pixels.size(); ++i) {
        for (int k = 0; k < 4; ++k) EXPECT_EQ(one.pixels[i][k], plain.pixels[i][k]) << i;
        sumPlain += plain.pixels[i].w, sumHalf += half.pixels[i].w, sumZero += zero.pixels[i].w;
    }
    EXPECT_GT(sumPlain, 10.0);
    EXPECT_EQ(sumZero, 0.0);
    EXPECT_LT(sumHalf, 0.9 * sumPlain);
    EXPECT_GT(sumHalf, 0.3 * sumPlain);
    const std::pair<const char*, const char*> bad[] = {
        {"--gradient-opacity 1:2", "--gradient-opacity 1:2: expected MAGNITUDE:SCALE"},
        {"--gradient-opacity 2:1,1:0", "--gradient-opacity 2:1,1:0: expected MAGNITUDE:SCALE"},
        {"--gradient-opacity x", "--gradient-opacity x: expected MAGNITUDE:SCALE"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr(fin + "-o x.png " + flags, dir), {says}, flags);
    const CliRun cells = uvr("-q render " + testing::sharedData("cylinder_quadratic_as_tets.vtk") +
                                 " --field pressure:cell --size 16x16 --gradient-opacity 0:1 "
                                 "-o x.png",
                             dir);
    expectOneLineError(cells, {"--gradient-opacity 0:1: a gradient opacity needs a point field"},
                       "cell data");
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(Cli, IsoDrawsSurfacesInsideTheVolumeAndIsReported) {
    // Issue 32: --iso draws opaque or translucent surfaces, lit with the shading coefficients
    // (read with --iso even without --shade); the stats list them as written; bad ones are
    // refused in one line, and cell data has none.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string fin = "-q render " + testing::sharedData("bluntfin_tets.vtk") +
                            " --size 48x32 --method exact --azimuth 30 --elevation 20 ";
    ASSERT_EQ(uvr(fin + "-o plain.png", dir).code, 0);
    const CliRun iso = uvr(
        fin + "-o iso.png --iso 0.9 --iso 1.2,0.5,#ff8000 --specular 0.2 --stats iso.json", dir);
    ASSERT_EQ(iso.code, 0) << iso.err;
    std::ifstream in(dir + "/iso.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["iso"], nlohmann::json::array({"0.9", "1.2,0.5,#ff8000"}));
    EXPECT_EQ(j["shade"], false);
    EXPECT_FLOAT_EQ(j["specular"].get<float>(), 0.2f);
    // The opaque surface covers pixels the thin volume leaves nearly transparent.
    const Image a = readPng(dir + "/plain.png"), b = readPng(dir + "/iso.png");
    int opaque = 0, before = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        before += a.pixels[i].w > 0.99f, opaque += b.pixels[i].w > 0.99f;
    EXPECT_GT(opaque, before + 50);
    const std::pair<const char*, const char*> bad[] = {
        {"--iso 0.5,2", "--iso 0.5,2: expected VALUE[,OPACITY[,#RRGGBB]]"},
        {"--iso x", "--iso x: expected VALUE[,OPACITY[,#RRGGBB]]"},
        {"--iso 1,1,red", "--iso 1,1,red: expected VALUE[,OPACITY[,#RRGGBB]]"},
        {"--iso 1 --iso 2 --iso 3 --iso 4 --iso 5 --iso 6 --iso 7 --iso 8 --iso 9",
         "--iso 9 isosurfaces: expected at most 8"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr(fin + "-o x.png " + flags, dir), {says}, flags);
    const CliRun cells = uvr("-q render " + testing::sharedData("cylinder_quadratic_as_tets.vtk") +
                                 " --field pressure:cell --size 16x16 --iso 0.5 -o x.png",
                             dir);
    expectOneLineError(cells, {"isosurfaces need a point field"}, "cell data");
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(Cli, DepthIsWrittenAndReadAsNpy) {
    // Issue 32: --depth writes where an opaque isosurface (or the opacity asked for) is, as a
    // .npy; --depth-in ends the rays there, so nothing behind the surface is added.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string fin = "-q render " + testing::sharedData("bluntfin_tets.vtk") +
                            " --size 48x32 --method exact --azimuth 30 --elevation 20 ";
    const CliRun out = uvr(fin + "-o iso.png --iso 0.9 --depth d.npy --stats d.json", dir);
    ASSERT_EQ(out.code, 0) << out.err;
    const std::vector<float> depth = readDepthNpy(dir + "/d.npy", 48, 32);
    int hits = 0;
    for (float z : depth) hits += std::isfinite(z);
    EXPECT_GT(hits, 100);
    std::ifstream in(dir + "/d.json");
    EXPECT_FLOAT_EQ(nlohmann::json::parse(in)["depth_alpha"].get<float>(), 0.5f);
    ASSERT_EQ(uvr(fin + "-o whole.png", dir).code, 0);
    const CliRun cut = uvr(fin + "-o cut.png --depth-in d.npy", dir);
    ASSERT_EQ(cut.code, 0) << cut.err;
    const Image whole = readPng(dir + "/whole.png"), front = readPng(dir + "/cut.png");
    for (std::size_t i = 0; i < depth.size(); ++i) {
        if (!std::isfinite(depth[i])) {
            EXPECT_EQ(front.pixels[i].w, whole.pixels[i].w) << i;
        } else {
            EXPECT_LE(front.pixels[i].w, whole.pixels[i].w + 1.f / 255.f) << i;
        }
    }
    const std::pair<const char*, const char*> bad[] = {
        {"--depth d.png", "--depth writes a NumPy array: name it *.npy"},
        {"--depth-opacity 0.3", "--depth-opacity sets what --depth writes: it needs --depth"},
        {"--depth-in iso.png", "not a depth image"},
    };
    for (const auto& [flags, says] : bad)
        expectOneLineError(uvr(fin + "-o x.png " + flags, dir), {says}, flags);
    expectOneLineError(uvr("-q render " + testing::sharedData("bluntfin_tets.vtk") +
                               " --size 8x8 --depth-in d.npy -o x.png",
                           dir),
                       {"shape (32, 48), but the frame is 8x8"}, "another size");
    EXPECT_FALSE(std::filesystem::exists(dir + "/x.png"));
}

TEST(Cli, FlagsThatWouldBeIgnoredOrMeanNothingAreRefused) {
    // Issue 15: one rule for every flag; every bad combination gets its one-line error.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string render =
        "-q render " + testing::sharedData("post_tets.vtk") + " --size 16x16 -o " + dir + "/a.png ";
    expectOneLineError(uvr(render + "--heatmap-max 5", dir), {"--heatmap-max", "needs --heatmap"},
                       "--heatmap-max alone");
    expectOneLineError(uvr(render + "--field density:x", dir),
                       {"--field 'density': a scalar field"}, "component of a scalar");
    expectOneLineError(uvr(render + "--field density:magnitude", dir), {"a scalar field"},
                       "magnitude of a scalar");
    expectOneLineError(uvr(render + "--background 1,2", dir),
                       {"--background '1,2'", "three finite numbers r,g,b"}, "--background");
    expectOneLineError(uvr(render + "--sample-distance 0", dir),
                       {"--sample-distance 0: expected a positive finite number"},
                       "--sample-distance 0");
    expectOneLineError(uvr(render + "--opacity-unit 0", dir),
                       {"--opacity-unit 0: expected a positive finite number"}, "--opacity-unit 0");
    // Flags the method ignores, named together with the method that reads them.
    expectOneLineError(uvr(render + "--method exact --sampling point --quality 0.9", dir),
                       {"--sampling and --quality are not read by --method exact"},
                       "two ignored flags");
    expectOneLineError(uvr(render + "--method reference --leaf-cells 64 --no-skip", dir),
                       {"--no-skip and --leaf-cells are not read by --method reference: they "
                        "need --method adaptive"},
                       "partition flags");
    // A vector's component and magnitude still work.
    EXPECT_EQ(uvr(render + "--field momentum:x", dir).code, 0);
    EXPECT_EQ(uvr(render + "--field momentum:magnitude", dir).code, 0);
}

TEST(Cli, MisspeltCommandsAndOptionsGetASuggestion) {
    // Issue 15: the unknown word named, the closest known one suggested (ParaView's names for
    // uvr's options too), and the --help of the subcommand in use.
    const std::string dir = testing::scratchDir();
    expectOneLineError(uvr("rendr x.vtk", dir),
                       {"unknown command 'rendr': did you mean 'render'?", "(see uvr --help)"},
                       "rendr");
    expectOneLineError(uvr("render x.vtk -o a.png --colormap viridis", dir),
                       {"unknown option --colormap (did you mean --tf?)", "uvr render --help"},
                       "--colormap");
    expectOneLineError(uvr("render x.vtk -o a.png --azimth 30", dir),
                       {"unknown option --azimth (did you mean --azimuth?)"}, "--azimth");
    expectOneLineError(uvr("info x.vtk --zzzzzzzz", dir),
                       {"unknown option --zzzzzzzz", "uvr info --help"}, "nothing close");
    EXPECT_EQ(uvr("info x.vtk --zzzzzzzz", dir).err.find("did you mean"), std::string::npos);
    EXPECT_EQ(editDistance("rendr", "render"), 1);
    EXPECT_EQ(cli::closest("--quailty", {"--quality", "--quiet"}), "--quality");
    EXPECT_EQ(cli::closest("--x", {"--quality"}), "");
}

TEST(Cli, PresetsListsParaViewNamesAndPresetsFiles) {
    // Issue 15: ParaView's preset names work with --tf, `uvr presets` lists them, and a presets
    // file of many maps gives one by name.
    const std::string dir = testing::scratchDir();
    const CliRun list = uvr("presets", dir);
    EXPECT_EQ(list.code, 0) << list.err;
    for (const char* name : {"Cool to Warm", "Viridis (matplotlib)", "Turbo", "Jet",
                             "Rainbow Uniform", "X Ray", "Blue Orange (divergent)"})
        EXPECT_NE(list.out.find(name), std::string::npos) << name;
    EXPECT_NE(list.out.find("Cool to Warm (Extended)  Lab        35 points"), std::string::npos)
        << list.out;
    const CliRun js = uvr("presets --json", dir);
    ASSERT_EQ(js.code, 0) << js.err;
    const nlohmann::json j = nlohmann::json::parse(js.out);
    EXPECT_EQ(j["source"], "built-in");
    ASSERT_GE(j["colormaps"].size(), 28u);
    EXPECT_EQ(j["colormaps"][0]["name"], "Cool to Warm");
    EXPECT_EQ(j["colormaps"][0]["color_space"], "Diverging");
    EXPECT_EQ(j["colormaps"][0]["points"], 3);

    const std::string file = testing::testData("presets/several_maps.json");
    const CliRun maps = uvr("presets " + file, dir);
    EXPECT_EQ(maps.code, 0) << maps.err;
    EXPECT_NE(maps.out.find("Ember Ramp    RGB        2 points"), std::string::npos) << maps.out;
    EXPECT_NE(maps.out.find("Site Classes  indexed    (not supported)"), std::string::npos)
        << maps.out;
    EXPECT_NE(maps.out.find("4 colour maps: --tf " + file + ":NAME"), std::string::npos);
    expectOneLineError(uvr("presets " + dir + "/missing.json", dir),
                       {dir + "/missing.json: cannot open"}, "missing file");
    expectOneLineError(uvr("presetz", dir), {"did you mean 'presets'?"}, "presetz");

    // Render with ParaView names and with a map of the presets file; refusals in one line.
    const std::string demo = "-q demo --cells 3000 --size 24x16 -o " + dir + "/d.png ";
    for (const std::string& tf :
         {std::string("Turbo"), std::string("'Rainbow Uniform'"), std::string("x-ray"),
          std::string("'Blue Orange'"), "'" + file + ":Ember Ramp'"}) {
        const CliRun r = uvr(demo + "--tf " + tf, dir);
        EXPECT_EQ(r.code, 0) << tf << ": " << r.err;
    }
    expectOneLineError(
        uvr(demo + "--tf jett", dir),
        {"unknown transfer function preset \"jett\"; did you mean \"Jet\"?", "`uvr presets` lists"},
        "jett");
    expectOneLineError(uvr(demo + "--tf " + file, dir),
                       {file + ": holds 4 colour maps: pick one with --tf " + file + ":NAME",
                        "\"Deep Sea\", \"Ember Ramp\""},
                       "no name");
    expectOneLineError(uvr(demo + "--tf '" + file + ":Amber Ramp'", dir),
                       {"no colour map named \"Amber Ramp\"; did you mean \"Ember Ramp\"?"},
                       "unknown name");
}

TEST(Cli, LogScaleAndNanColorFlags) {
    const std::string dir = testing::scratchDir();
    const std::string demo = "-q demo --cells 3000 --size 24x16 -o " + dir + "/d.png ";
    const CliRun ok = uvr(demo + "--log --range 0,1 --stats " + dir + "/s.json", dir);
    EXPECT_EQ(ok.code, 0) << ok.err;
    EXPECT_NE(ok.err.find("uvr: warning: demo: --log: --range [0, 1] is not positive; mapping "
                          "[0.0001, 1] as ParaView does"),
              std::string::npos)
        << ok.err;
    std::ifstream in(dir + "/s.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_EQ(stats["log_scale"], true);
    EXPECT_GT(stats["tf_table_entries"].get<int>(), 1024);
    EXPECT_FLOAT_EQ(stats["range"][0].get<float>(), 1e-4f);
    expectOneLineError(uvr(demo + "--log --range -2,0", dir),
                       {"--log needs positive values: --range [-2, 0] has none"}, "negative");
    expectOneLineError(uvr(demo + "--log-scale", dir), {"did you mean --log?"}, "--log-scale");
    // --nan-color r,g,b[,a].
    EXPECT_EQ(uvr(demo + "--nan-color 1,0,0", dir).code, 0);
    EXPECT_EQ(uvr(demo + "--nan-color 1,0,0,0.5", dir).code, 0);
    for (const char* bad : {"1,0", "2,0,0", "1,0,0,0,1", "red"})
        expectOneLineError(uvr(demo + "--nan-color " + bad, dir),
                           {"--nan-color '" + std::string(bad) + "': expected r,g,b or r,g,b,a"},
                           bad);
    expectOneLineError(uvr(demo + "--nan-colour 1,0,0", dir), {"did you mean --nan-color?"},
                       "--nan-colour");
}

TEST(Cli, EmptyImagesWarnWithTheReasonAndExitZero) {
    // Issue 15: a transparent image with exit 0 and no word is a trap; each cause is named.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx = testing::sharedData("spx.vtk");
    const std::string post = testing::sharedData("post_tets.vtk");
    const struct {
        std::string args, reason;
    } cases[] = {
        {post + " --field density", "the field is constant (1)"},
        {spx + " --range 100,200", "--range 100,200 misses the field's values"},
        {spx + " --camera-focal 100,100,100", "the mesh is not in view"},
        {spx + " --view-angle 179", "smaller than a pixel"},
        {spx + " --opacity constant:0", "opacity is 0 over all the field's values"},
        {spx + " --method exact --opacity constant:0", "opacity is 0 over all the field's values"},
        {spx + " --opacity constant:0.0000001", "below half an 8-bit level"},
    };
    for (const auto& c : cases) {
        const CliRun r = uvr("-q render " + c.args + " --size 32x32 -o " + dir + "/e.png", dir);
        EXPECT_EQ(r.code, 0) << c.args << ": " << r.err;
        EXPECT_NE(r.err.find("uvr: warning: "), std::string::npos) << c.args << ": " << r.err;
        EXPECT_NE(r.err.find(c.reason), std::string::npos) << c.args << ": " << r.err;
        EXPECT_EQ(readPng(dir + "/e.png").width, 32) << c.args;  // the image is still written
    }
    // A picture with something in it: no warning.
    const CliRun ok = uvr("-q render " + spx + " --size 32x32 -o " + dir + "/f.png", dir);
    EXPECT_EQ(ok.code, 0) << ok.err;
    EXPECT_EQ(ok.err.find("warning"), std::string::npos) << ok.err;
}

TEST(Cli, BenchPrintsEveryConfigurationAndWritesItsFiles) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const CliRun r = uvr("-q bench " + testing::sharedData("spx.vtk") +
                             " --size 48x48 --repeat 1 --sweep 2,4 --csv " + dir +
                             "/b.csv --json " + dir + "/b.json --images " + dir,
                         dir);
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* row : {"exact (1 frame)", "reference", "skipping only", "adaptive only",
                            "skipping + adaptive", "reference, point", "paper: variance, point",
                            "auto: exact", "both, s2 = 2 s1", "both, s2 = 4 s1"})
        EXPECT_NE(r.out.find(row), std::string::npos) << row;
    std::ifstream in(dir + "/b.json");
    const auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j["rows"].size(), 9u);
    EXPECT_EQ(j["step_rule"], "error");
    EXPECT_EQ(j["sampling"], "preintegrated");
    EXPECT_EQ(j["ssim_against"], "exact");
    EXPECT_GT(j["exact"]["tetrahedra_crossed"].get<double>(), 0);
    // Against the exact image: the reference close, skipping only takes the same samples.
    const double ref = j["rows"][0]["ssim"].get<double>();
    EXPECT_GE(ref, 0.98);
    EXPECT_LT(ref, 1.0);
    EXPECT_NEAR(j["rows"][1]["ssim"].get<double>(), ref, 0.005);
    // The default's row: auto picks exact on SPX, so its image is the yardstick's.
    EXPECT_EQ(j["rows"][6]["configuration"], "auto: exact");
    EXPECT_EQ(j["rows"][6]["max_abs_difference"].get<double>(), 0.0);
    EXPECT_TRUE(std::filesystem::exists(dir + "/exact.png"));
    // The per-pixel measures against exact (issue 29), by their one name, in JSON, CSV, text.
    for (const ComparisonField& f : differenceFields(ImageComparison{})) {
        EXPECT_TRUE(j["rows"][0].contains(f.name)) << f.name;
        EXPECT_NE(testing::readFile(dir + "/b.csv").find(std::string(",") + f.name),
                  std::string::npos)
            << f.name;
    }
    EXPECT_GE(j["rows"][0]["p999_difference"].get<double>(), 0.0);
    EXPECT_LE(j["rows"][0]["p999_difference"].get<double>(),
              j["rows"][0]["max_abs_difference"].get<double>());
    EXPECT_NE(r.out.find("p99.9"), std::string::npos) << r.out;
    // What bench/plot_bench.py draws from: each row's images and the heat maps' scale.
    EXPECT_EQ(j["rows"][0]["image"], "reference");
    EXPECT_EQ(j["images"], dir);
    EXPECT_EQ(j["heatmap"]["colors"].size(), 64u);
    EXPECT_GT(j["heatmap"]["max_samples"].get<double>(), 0);
    EXPECT_TRUE(std::filesystem::exists(dir + "/reference_samples.png"));
    // Names that read as names (issue 15; they were "both__s2___16_s1.png").
    EXPECT_TRUE(std::filesystem::exists(dir + "/skipping-adaptive.png"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/adaptive_s2-4.png"));
    // A missing --images folder is made (it was "not a folder").
    ASSERT_EQ(uvr("-q bench " + testing::sharedData("spx.vtk") +
                      " --size 16x16 --repeat 1 --sweep 2 --images " + dir + "/new/images",
                  dir)
                  .code,
              0);
    EXPECT_TRUE(std::filesystem::exists(dir + "/new/images/adaptive_s2-2.png"));
    EXPECT_TRUE(std::filesystem::exists(dir + "/b.csv"));
}

/// Starts `uvr ARGS` with stderr to errPath, waits until that stderr holds `marker` (or the run
/// ends), sends it SIGTERM and returns its wait status.
int interruptWhenLogged(const std::vector<std::string>& args, const std::string& errPath,
                        const std::string& marker) {
    const pid_t pid = ::fork();
    if (pid == 0) {
        const int fd = ::open(errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(fd, 2);
        std::vector<char*> argv;
        const std::string bin = testing::uvrBinary();
        argv.push_back(const_cast<char*>(bin.c_str()));
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        ::execv(bin.c_str(), argv.data());
        ::_exit(127);
    }
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
        std::ifstream in(errPath);
        const std::string log((std::istreambuf_iterator<char>(in)), {});
        if (log.find(marker) != std::string::npos) {
            ::kill(pid, SIGTERM);
            ::waitpid(pid, &status, 0);
            return status;
        }
        ::usleep(2000);
    }
    return status;
}

/// Names of the files in a folder, sorted.
std::vector<std::string> fileNames(const std::string& dir) {
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        files.push_back(e.path().filename().string());
    std::sort(files.begin(), files.end());
    return files;
}

TEST(Cli, InterruptedRenderLeavesThePreviousOutputUntouched) {
    // Killed while rendering (SIGTERM after the "rendering" progress line), uvr must leave the
    // existing output as it was and no partial or temporary file beside it.
    const std::string dir = testing::scratchDir();
    const std::string out = dir + "/out.png";
    testing::writeFile(out, "previous image");
    const int status = interruptWhenLogged(
        {"demo", "--cells", "20000", "--size", "4096x4096", "--threads", "1", "-o", out},
        dir + "/log.txt", "uvr: rendering jet (point data)");
    ASSERT_TRUE(WIFSIGNALED(status)) << "the render finished before it could be interrupted";
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    std::ifstream in(out);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(in)), {}), "previous image");
    EXPECT_EQ(fileNames(dir), (std::vector<std::string>{"log.txt", "out.png"}));
}

TEST(Cli, InterruptedConvertLeavesNoTemporary) {
    // SIGTERM while the output mesh is being written (after the "read" line): the old output
    // stays, the temporary beside it is removed by the signal handler.
    const std::string dir = testing::scratchDir();
    const std::string in = dir + "/in.uvrm", out = dir + "/out.vtu";
    ASSERT_EQ(uvr("-q generate box --cells 1500000 -o " + in, dir).code, 0);
    std::filesystem::remove(dir + "/stdout.txt");
    std::filesystem::remove(dir + "/stderr.txt");
    testing::writeFile(out, "previous mesh");
    const int status = interruptWhenLogged({"convert", in, out}, dir + "/log.txt", "uvr: read ");
    ASSERT_TRUE(WIFSIGNALED(status)) << "the conversion finished before it could be interrupted";
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    std::ifstream old(out);
    EXPECT_EQ(std::string((std::istreambuf_iterator<char>(old)), {}), "previous mesh");
    EXPECT_EQ(fileNames(dir), (std::vector<std::string>{"in.uvrm", "log.txt", "out.vtu"}));
}

/// A legacy VTK cube of five tetrahedra with point field `name` holding `values` (8 numbers).
std::string fiveTetCube(const std::string& name, const std::string& values) {
    return cli_testing::fiveTetCubeVtk("POINT_DATA 8\nSCALARS " + name +
                                       " float 1\nLOOKUP_TABLE default\n" + values + "\n");
}

TEST(Cli, FieldSpanningTheWholeFloatRangeRendersWithBothMethods) {
    // The range's width overflows float: it used to crash both integrators (SIGSEGV).
    const std::string dir = testing::scratchDir();
    const std::string mesh = testing::writeFile(
        dir + "/huge.vtk", fiveTetCube("f", "-3e38 3e38 -3e38 3e38 3e38 -3e38 3e38 -3e38"));
    for (const char* method : {"reference", "adaptive"}) {
        const std::string png = dir + "/" + method + ".png", stats = dir + "/" + method + ".json";
        const CliRun r =
            uvr("-q render " + mesh + " --method " + method +
                    " --size 32x32 --opacity constant:0.5 -o " + png + " --stats " + stats,
                dir);
        ASSERT_EQ(r.code, 0) << method << ": " << r.err;
        std::ifstream in(stats);
        const auto j = nlohmann::json::parse(in);
        EXPECT_FLOAT_EQ(j["range"][0].get<float>(), -3e38f);
        EXPECT_FLOAT_EQ(j["range"][1].get<float>(), 3e38f);
        const Image img = readPng(png);
        int covered = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) covered += img.at(x, y).w > 0.1f;
        EXPECT_GT(covered, 100) << method;
    }
}

TEST(Cli, NamesWithInvalidUtf8OrControlCharactersStayValidJsonAndOneLine) {
    const std::string dir = testing::scratchDir();
    // A field name with bytes that are not UTF-8 and an escape sequence (legal in VTK files).
    const std::string bad =
        testing::writeFile(dir + "/bad.vtk", fiveTetCube("f\xff\xfe\x1b[31m", "0 1 2 3 4 5 6 7"));
    const CliRun info = uvr("-q info --json " + bad, dir);
    ASSERT_EQ(info.code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);  // throws on invalid JSON
    ASSERT_EQ(j["fields"].size(), 1u);
    EXPECT_EQ(j["fields"][0]["name"].get<std::string>().substr(0, 1), "f");
    const CliRun text = uvr("-q info " + bad, dir);
    ASSERT_EQ(text.code, 0) << text.err;
    EXPECT_NE(text.out.find("f\\xff\\xfe\\x1b[31m"), std::string::npos) << text.out;
    EXPECT_EQ(text.out.find('\x1b'), std::string::npos);
    const CliRun render = uvr(
        "-q render " + bad + " --size 16x16 -o " + dir + "/b.png --stats " + dir + "/b.json", dir);
    ASSERT_EQ(render.code, 0) << render.err;
    std::ifstream in(dir + "/b.json");
    EXPECT_EQ(nlohmann::json::parse(in)["field"].get<std::string>().substr(0, 1), "f");
    // Errors quoting the name stay one line, escaped.
    expectOneLineError(uvr("-q render " + bad + " -o " + dir + "/c.png --field nosuch", dir),
                       {"f\\xff\\xfe\\x1b[31m"}, "unknown field");
    // A file name with a newline: progress lines and the error stay one line each.
    const std::string newline = testing::writeFile(dir + "/new\nline.vtk", "not a mesh\n");
    const CliRun r = uvr("render '" + newline + "' -o " + dir + "/d.png", dir);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.find("\nline.vtk"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("uvr: error: " + dir + "/new\\nline.vtk: "), std::string::npos) << r.err;
}

TEST(Cli, SameNamedFieldsAreListedByInfoAndNamedRightByRender) {
    const std::string dir = testing::scratchDir();
    const std::string two = testing::writeFile(
        dir + "/two.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7") +
                              "SCALARS f float 1\nLOOKUP_TABLE default\n7 6 5 4 3 2 1 9\n");
    const CliRun info = uvr("-q info --json " + two, dir);
    ASSERT_EQ(info.code, 0) << info.err;
    const auto j = nlohmann::json::parse(info.out);
    ASSERT_EQ(j["fields"].size(), 2u);
    EXPECT_EQ(j["fields"][1]["range"][1].get<double>(), 9.0);
    ASSERT_EQ(j["validation"].size(), 1u);
    EXPECT_EQ(j["validation"][0]["code"], "duplicate_field_names");
    EXPECT_EQ(j["validation"][0]["count"], 2);
    EXPECT_EQ(j["validation"][0]["field"], "f");
    EXPECT_NE(j["validation"][0]["message"].get<std::string>().find("2 point fields are named 'f'"),
              std::string::npos);
    const CliRun render = uvr("-q render " + two + " -o " + dir + "/t.png --field f", dir);
    expectOneLineError(render, {"--field 'f'", "2 point fields", "cannot tell them apart"},
                       "duplicate field");
    EXPECT_EQ(render.err.find("point and cell"), std::string::npos) << render.err;
}

TEST(Cli, ThreadCountsFollowOneRuleInEveryCommand) {
    const std::string dir = testing::scratchDir();
    const std::string mesh =
        testing::writeFile(dir + "/m.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7"));
    const std::string render = "-q render " + mesh + " --size 8x8 -o " + dir + "/o.png";
    for (const std::string& cmd : {render, "-q demo --cells 1000 --size 8x8 -o " + dir + "/d.png",
                                   "-q bench " + mesh + " --size 16x16 --repeat 1 --sweep 2",
                                   "-q refine " + mesh + " " + dir + "/r.uvrm"}) {
        for (const char* bad : {"4096", "-1"})
            expectOneLineError(uvr(cmd + " --threads " + bad, dir),
                               {std::string("--threads ") + bad + ": expected 1 to "}, cmd);
        // 0 is the default (OMP_NUM_THREADS, else all cores) for every command.
        const CliRun zero = uvr(cmd + " --threads 0", dir);
        EXPECT_EQ(zero.code, 0) << cmd << ": " << zero.err;
    }
    // An environment asking for thousands of threads is capped with a note.
    const CliRun env = uvr(render + " --stats " + dir + "/s.json", dir, "OMP_NUM_THREADS=5000 ");
    ASSERT_EQ(env.code, 0) << env.err;
    EXPECT_NE(env.err.find("uvr: note: OMP_NUM_THREADS=5000 is more than"), std::string::npos)
        << env.err;
    std::ifstream in(dir + "/s.json");
    EXPECT_LE(nlohmann::json::parse(in)["threads"].get<int>(), 1024);
}

TEST(Cli, MeaninglessValuesAndUnreadableTextAreRefusedInOneLine) {
    const std::string dir = testing::scratchDir();
    const std::string mesh =
        testing::writeFile(dir + "/m.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7"));
    const std::string render = "-q render " + mesh + " --size 8x8 -o " + dir + "/o.png ";
    expectOneLineError(uvr(render + "--opacity ''", dir), {"--opacity \"\": empty spec"},
                       "empty opacity");
    for (const char* angle : {"1e-30", "0.001", "179.5", "nan", "inf", "-5"})
        expectOneLineError(uvr(render + "--view-angle " + angle, dir),
                           {"--view-angle ", "expected degrees in [0.01, 179]"}, angle);
    EXPECT_EQ(uvr(render + "--view-angle 0.5", dir).code, 0);
    // A colour map in UTF-16 and one nested 100,000 deep (a stack overflow before).
    std::string utf16 = "\xFF\xFE";
    for (char c : std::string("[{\"RGBPoints\": [0, 1, 1, 1]}]")) utf16 += std::string{c, '\0'};
    const std::string wide = testing::writeFile(dir + "/wide.json", utf16);
    expectOneLineError(uvr(render + "--tf " + wide, dir),
                       {wide + ": byte 0: UTF-16 text is not supported"}, "UTF-16 JSON");
    const std::string deep =
        testing::writeFile(dir + "/deep.json", std::string(100000, '[') + std::string(100000, ']'));
    expectOneLineError(uvr(render + "--tf " + deep, dir),
                       {deep + ": byte 64: JSON nested deeper than 64 levels"}, "deep JSON");
    // A camera file in UTF-32 (UTF-16 is XML's other required encoding, and is read).
    std::string utf32 = "\xFF\xFE";
    utf32 += std::string("\0\0", 2);
    for (char c : std::string("<?xml version=\"1.0\"?><PVCameraConfiguration/>"))
        utf32 += std::string{c, '\0', '\0', '\0'};
    const std::string cam = testing::writeFile(dir + "/cam.pvcc", utf32);
    expectOneLineError(uvr(render + "--camera " + cam, dir),
                       {cam + ": byte 0: UTF-32 text is not supported"}, "UTF-32 camera");
    // A camera file whose number_of_elements disagrees with its elements.
    const std::string declared = testing::writeFile(
        dir + "/declared.pvcc",
        "<?xml version=\"1.0\"?>\n<PVCameraConfiguration>\n"
        "  <Property name=\"CameraPosition\" number_of_elements=\"4\">\n"
        "    <Element index=\"0\" value=\"3\"/><Element index=\"1\" value=\"2\"/>"
        "<Element index=\"2\" value=\"4\"/>\n  </Property>\n</PVCameraConfiguration>\n");
    expectOneLineError(uvr(render + "--camera " + declared, dir),
                       {declared + ": line 3: property CameraPosition: expected "
                                   "number_of_elements=\"3\", got \"4\""},
                       "declared count");
}

TEST(Cli, CameraAndMemoryErrorsNameTheFile) {
    const std::string dir = testing::scratchDir();
    // No points: nothing to fit the default camera to (or to render).
    const std::string empty = testing::writeFile(
        dir + "/empty.vtk",
        "# vtk DataFile Version 3.0\nempty\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 float\n"
        "CELLS 0 0\nCELL_TYPES 0\nCELL_DATA 0\nSCALARS c float 1\nLOOKUP_TABLE default\n");
    expectOneLineError(uvr("-q render " + empty + " -o " + dir + "/e.png", dir),
                       {"uvr: error: " + empty + ": "}, "empty mesh");
    // Out of memory (an address-space limit the image buffers exceed): the file and the step.
    // Not under AddressSanitizer, whose shadow memory alone exceeds any such limit.
    if (testing::underAddressSanitizer()) return;
    const std::string mesh =
        testing::writeFile(dir + "/m.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7"));
    const CliRun r =
        uvr("-q render " + mesh +
                " --device cpu --threads 2 --size 12000x12000 --max-memory 8G -o " + dir + "/o.png",
            dir, "ulimit -v 1000000; ");
    expectOneLineError(r, {"uvr: error: " + mesh + ": "}, "out of memory");
    if (r.err.find("out of memory") != std::string::npos) {
        EXPECT_NE(r.err.find(mesh + ": out of memory while rendering it at 12000x12000"),
                  std::string::npos)
            << r.err;
    }
}

TEST(Cli, ConvertAndGenerateRefuseAnUnwritableFormatBeforeAnyWork) {
    // Issue 15: the output's format was refused only after reading or generating the mesh.
    const std::string dir = testing::scratchDir();
    const std::string mesh =
        testing::writeFile(dir + "/m.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7"));
    for (const std::string& cmd : {"convert " + mesh + " " + dir + "/x.abc",
                                   "generate box --cells 1000 -o " + dir + "/x.abc",
                                   "refine " + mesh + " " + dir + "/x.abc"}) {
        const CliRun r = uvr(cmd, dir);
        expectOneLineError(r, {"x.abc", "cannot write this format"}, cmd);
        // Nothing was read or generated first.
        EXPECT_EQ(r.err.find("uvr: read "), std::string::npos) << cmd << ": " << r.err;
        EXPECT_EQ(r.err.find("generated"), std::string::npos) << cmd << ": " << r.err;
    }
}

TEST(Cli, OutputsNeverDestroyWhatTheirPathNames) {
    const std::string dir = testing::scratchDir();
    const std::string mesh =
        testing::writeFile(dir + "/m.vtk", fiveTetCube("f", "0 1 2 3 4 5 6 7"));
    const std::string render = "-q render " + mesh + " --size 16x16 --device cpu ";
    auto names = [&] {  // without the runs' captured output
        std::vector<std::string> files = fileNames(dir);
        std::erase_if(files,
                      [](const std::string& f) { return f == "stdout.txt" || f == "stderr.txt"; });
        return files;
    };
    // Onto the input mesh (also through a symbolic link), or two outputs onto one file.
    std::filesystem::create_symlink("m.vtk", dir + "/alias.vtk");
    expectOneLineError(uvr(render + "-o " + dir + "/alias.vtk", dir),
                       {"-o names the input mesh", "refusing to overwrite an input"}, "-o mesh");
    expectOneLineError(uvr(render + "-o " + dir + "/a.png --heatmap " + dir + "/a.png", dir),
                       {"--heatmap names the same file as -o"}, "two outputs");
    expectOneLineError(uvr("-q convert " + mesh + " " + mesh, dir), {"OUT names the input mesh"},
                       "convert onto itself");
    // The name must say what is written (issue 15: `-o a.jpg` wrote PNG bytes).
    expectOneLineError(uvr(render + "-o " + dir + "/a.jpg", dir),
                       {"a.jpg", "-o writes a PNG image: name it *.png"}, "-o a.jpg");
    expectOneLineError(uvr(render + "-o " + dir + "/a", dir), {"-o writes a PNG image"}, "-o a");
    expectOneLineError(uvr(render + "-o " + dir + "/a.png --heatmap " + dir + "/h.jpeg", dir),
                       {"--heatmap writes a PNG image"}, "--heatmap h.jpeg");
    expectOneLineError(uvr(render + "-o " + dir + "/a.png --stats " + dir + "/s.txt", dir),
                       {"--stats writes JSON: name it *.json"}, "--stats s.txt");
    EXPECT_EQ(uvr(render + "-o " + dir + "/upper.PNG", dir).code, 0);
    std::filesystem::remove(dir + "/upper.PNG");
    EXPECT_EQ(names(), (std::vector<std::string>{"alias.vtk", "m.vtk"}));
    EXPECT_EQ(readMesh(mesh).cellCount(), 5u);
    // A character device is written in place, never replaced.
    EXPECT_EQ(uvr(render + "-o /dev/null --stats /dev/null", dir).code, 0);
    struct stat st;
    ASSERT_EQ(::stat("/dev/null", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
    // "-": the PNG on standard output (a file here).
    const CliRun piped = uvr(render + "-o -", dir);
    EXPECT_EQ(piped.code, 0) << piped.err;
    EXPECT_EQ(piped.out.substr(0, 4), "\x89PNG");
    // A full device: exit 2, one line, and none of the render's other outputs appears.
    if (std::filesystem::exists("/dev/full")) {
        expectOneLineError(uvr(render + "-o " + dir + "/a.png --stats /dev/full", dir),
                           {"/dev/full: cannot write", "No space left on device"}, "--stats full");
        expectOneLineError(uvr(render + "-o /dev/full", dir), {"/dev/full: cannot write"},
                           "-o full");
        expectOneLineError(
            uvr("-q bench " + mesh + " --size 16x16 --repeat 1 --json /dev/full", dir),
            {"/dev/full: cannot write"}, "bench --json full");
        expectOneLineError(
            uvr("-q bench " + mesh + " --size 16x16 --repeat 1 --csv /dev/full", dir),
            {"/dev/full: cannot write"}, "bench --csv full");
        EXPECT_EQ(names(), (std::vector<std::string>{"alias.vtk", "m.vtk"}));
    }
}

TEST(Cli, LinksPlantedInASharedFolderByAnotherUserAreNotFollowed) {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to give links to another user";
    namespace fs = std::filesystem;
    const std::string dir = testing::scratchDir();
    const std::string cube = fiveTetCube("f", "0 1 2 3 4 5 6 7");
    const std::string mesh = testing::writeFile(dir + "/cube.vtk", cube);
    const std::string shared = dir + "/shared";  // as /tmp: sticky, writable by everyone
    fs::create_directory(shared);
    ASSERT_EQ(::chmod(shared.c_str(), 01777), 0);
    const std::string victim = testing::writeFile(dir + "/victim", "precious");
    const auto plant = [&](const std::string& name) {  // another user's link to the victim
        const std::string link = shared + "/" + name;
        fs::create_symlink(victim, link);
        EXPECT_EQ(::lchown(link.c_str(), 65534, 65534), 0);
        return link;
    };
    const std::string render = "-q render " + mesh + " --size 16x16 --device cpu ";
    const std::string refused = "refusing to follow the symbolic link '" + shared;
    expectOneLineError(
        uvr(render + "-o " + plant("out.png"), dir),
        {refused + "/out.png' owned by uid 65534", "in the shared folder '" + shared + "'"}, "-o");
    expectOneLineError(uvr(render + "-o " + dir + "/a.png --stats " + plant("s.json"), dir),
                       {refused + "/s.json'"}, "--stats");
    expectOneLineError(uvr(render + "-o " + dir + "/a.png --heatmap " + plant("h.png"), dir),
                       {refused + "/h.png'"}, "--heatmap");
    plant("frame_0000.png");
    expectOneLineError(uvr("-q animate " + mesh + " --size 16x16 --device cpu -o " + shared, dir),
                       {refused + "/frame_0000.png'"}, "animate");
    testing::writeFile(shared + "/cube.vtk", cube);
    plant("cube.vtk.uvrprep");
    expectOneLineError(uvr("-q prepare " + shared + "/cube.vtk --device cpu", dir),
                       {refused + "/cube.vtk.uvrprep'"}, "prepare");
    EXPECT_EQ(testing::readFile(victim), "precious");
    EXPECT_FALSE(fs::exists(dir + "/a.png"));
    EXPECT_EQ(fileNames(shared),
              (std::vector<std::string>{"cube.vtk", "cube.vtk.uvrprep", "frame_0000.png", "h.png",
                                        "out.png", "s.json"}));
    // The user's own link there is followed.
    ASSERT_EQ(::lchown((shared + "/out.png").c_str(), 0, 0), 0);
    const CliRun r = uvr(render + "-o " + shared + "/out.png", dir);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(fs::is_symlink(shared + "/out.png"));
    EXPECT_EQ(testing::readFile(victim).substr(1, 3), "PNG");
}

TEST(Cli, TheLogSaysWhenThePngIsTransparent) {
    // Issue 35: the default PNG is transparent (washed out on white); the log says so.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string base = "render " + testing::sharedData("spx.vtk") +
                             " --size 32x32 --device cpu --stats s.json -o a.png";
    const CliRun clear = uvr(base, dir);
    ASSERT_EQ(clear.code, 0) << clear.err;
    EXPECT_NE(clear.err.find("a.png (a transparent RGBA PNG: --background R,G,B"),
              std::string::npos)
        << clear.err;
    EXPECT_EQ(clear.err.find("s.json (a transparent"), std::string::npos) << clear.err;
    const CliRun black = uvr(base + " --background 0,0,0", dir);
    ASSERT_EQ(black.code, 0) << black.err;
    EXPECT_EQ(black.err.find("transparent"), std::string::npos) << black.err;
}

}  // namespace
}  // namespace uvr

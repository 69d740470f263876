// SPDX-License-Identifier: MIT
// End-to-end tests of `--legend`: the colour legend composited onto rendered images.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"
#include "uvr/annotate/font.h"
#include "uvr/render/image.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;

/// Pixels that differ between two images of the same size in columns [x0, x1).
int differingPixels(const Image& a, const Image& b, int x0, int x1) {
    int n = 0;
    for (int y = 0; y < a.height; ++y)
        for (int x = x0; x < x1; ++x) {
            const Vec4f p = a.at(x, y), q = b.at(x, y);
            n += p.x != q.x || p.y != q.y || p.z != q.z || p.w != q.w;
        }
    return n;
}

/// The camera flags of the camera a --stats report names.
std::string cameraFlags(const std::string& statsFile) {
    std::ifstream in(statsFile);
    const nlohmann::json cam = nlohmann::json::parse(in)["camera"];
    const auto v = [&](const char* key) {
        std::ostringstream s;
        s.precision(9);
        s << cam[key][0].get<double>() << "," << cam[key][1].get<double>() << ","
          << cam[key][2].get<double>();
        return s.str();
    };
    return " --camera-position " + v("position") + " --camera-focal " + v("focal_point") +
           " --camera-up " + v("view_up");
}

/// Columns [x0, x1) show only the background (the top-right corner's colour) in every row.
bool clear(const Image& a, int x0, int x1) {
    const Vec4f bg = a.at(a.width - 1, 0);
    for (int y = 0; y < a.height; ++y)
        for (int x = x0; x < x1; ++x) {
            const Vec4f p = a.at(x, y);
            if (p.x != bg.x || p.y != bg.y || p.z != bg.z || p.w != bg.w) return false;
        }
    return true;
}

TEST(Cli, TheLegendKeepsTheVolumeOffItself) {
    // Issue 35: with the reset camera (turned or not) the volume moves left of the legend's
    // columns; a camera the user placed stays, and the legend then changes only its part.
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    if (!textEngineAvailable()) GTEST_SKIP() << "built without text (UVR_ENABLE_TEXT=OFF)";
    const std::string dir = testing::scratchDir();
    const std::string base =
        "-q render " + testing::sharedData("spx.vtk") + " --size 320x240 --device cpu --tf viridis";
    for (const auto& [turn, background] :
         {std::pair<std::string, std::string>{"", ""},
          {" --azimuth 40 --elevation 20", " --background 1,1,1"}}) {
        const std::string extra = turn + background;
        SCOPED_TRACE(extra);
        CliRun r = uvr(base + extra + " -o plain.png", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        r = uvr(base + extra + " --legend -o legend.png --stats legend.json", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_EQ(r.err, "");
        // The same moved camera without the legend: the volume is clear of the right quarter
        // (the legend's columns here), and the two images agree left of them.
        r = uvr(base + background + cameraFlags(dir + "/legend.json") + " -o moved.png", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        const Image plain = readPng(dir + "/plain.png"), legend = readPng(dir + "/legend.png"),
                    moved = readPng(dir + "/moved.png");
        ASSERT_EQ(legend.width, 320);
        ASSERT_EQ(legend.height, 240);
        EXPECT_GT(differingPixels(plain, moved, 0, 320), 2000);  // the camera moved
        // The legend's box starts where the two first differ; the volume keeps off it.
        int box = 0;
        while (box < 320 && differingPixels(moved, legend, box, box + 1) == 0) ++box;
        EXPECT_GT(box, 160);
        EXPECT_LT(box, 260);
        EXPECT_TRUE(clear(moved, box, 320));
        EXPECT_GT(differingPixels(moved, legend, box, 320), 2000);
        if (extra.empty()) {
            EXPECT_FALSE(clear(plain, box, 320));  // the volume reached there before
            // On a transparent image the legend has its own backing: nothing near the right
            // edge at mid-height is transparent.
            EXPECT_GE(legend.at(300, 120).w, 0.79f);
        }
        // A placed camera stays: the legend changes only the right part.
        r = uvr(base + background + cameraFlags(dir + "/legend.json") + " --legend -o placed.png",
                dir);
        ASSERT_EQ(r.code, 0) << r.err;
        const Image placed = readPng(dir + "/placed.png");
        EXPECT_EQ(differingPixels(moved, placed, 0, 200), 0);
        EXPECT_EQ(differingPixels(legend, placed, 0, 320), 0);
    }
    // demo draws one too, its volume moved left likewise.
    CliRun r = uvr("-q demo --cells 3000 --size 200x150 --legend -o demo.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q demo --cells 3000 --size 200x150 -o plain.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const Image demo = readPng(dir + "/demo.png"), plain = readPng(dir + "/plain.png");
    EXPECT_GT(differingPixels(plain, demo, 0, 80), 500);
    EXPECT_GT(differingPixels(plain, demo, 150, 200), 500);
}

TEST(Cli, LegendRefusesATinyImageAndAMissingFontInOneLine) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    const std::string spx = testing::sharedData("spx.vtk");
    CliRun r = uvr("render " + spx + " -o a.png --size 100x300 --legend", dir);
    expectOneLineError(r, {"--legend", "128x128", "100x300"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.png"));
    r = uvr("render " + spx + " -o a.png --size 300x127 --legend", dir);
    expectOneLineError(r, {"--legend", "128x128"});
    // A fontconfig without font folders: the package to install is named; nothing is written.
    testing::writeFile(dir + "/fonts.conf", "<?xml version=\"1.0\"?>\n<fontconfig>\n<cachedir>" +
                                                dir + "/cache</cachedir>\n</fontconfig>\n");
    r = uvr("render " + spx + " -o a.png --size 300x300 --legend", dir,
            "FONTCONFIG_FILE=" + dir + "/fonts.conf ");
    expectOneLineError(
        r, {"--legend", textEngineAvailable() ? "fonts-dejavu-core" : "libfreetype-dev"});
    EXPECT_FALSE(std::filesystem::exists(dir + "/a.png"));
    EXPECT_EQ(r.err.find("reading"), std::string::npos) << "refused after reading: " << r.err;
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// End-to-end tests of `--legend`: the colour legend composited onto rendered images.
#include <gtest/gtest.h>

#include <filesystem>
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

TEST(Cli, LegendChangesOnlyTheRightPartOfTheImage) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    if (!textEngineAvailable()) GTEST_SKIP() << "built without text (UVR_ENABLE_TEXT=OFF)";
    const std::string dir = testing::scratchDir();
    const std::string base =
        "-q render " + testing::sharedData("spx.vtk") + " --size 320x240 --device cpu --tf viridis";
    for (const std::string background : {"", " --background 1,1,1"}) {
        CliRun r = uvr(base + background + " -o plain.png", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        r = uvr(base + background + " --legend -o legend.png", dir);
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_EQ(r.err, "");
        const Image plain = readPng(dir + "/plain.png"), legend = readPng(dir + "/legend.png");
        ASSERT_EQ(legend.width, 320);
        ASSERT_EQ(legend.height, 240);
        EXPECT_EQ(differingPixels(plain, legend, 0, 160), 0) << background;
        EXPECT_GT(differingPixels(plain, legend, 160, 320), 2000) << background;
        if (background.empty()) {
            // On a transparent image the legend has its own backing: nothing near the right
            // edge at mid-height is transparent.
            EXPECT_EQ(plain.at(300, 120).w, 0.f);
            EXPECT_GE(legend.at(300, 120).w, 0.79f);
        }
    }
    // demo draws one too.
    CliRun r = uvr("-q demo --cells 3000 --size 200x150 --legend -o demo.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    r = uvr("-q demo --cells 3000 --size 200x150 -o plain.png", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const Image demo = readPng(dir + "/demo.png"), plain = readPng(dir + "/plain.png");
    EXPECT_EQ(differingPixels(plain, demo, 0, 80), 0);
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

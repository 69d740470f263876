// SPDX-License-Identifier: MIT
#include "uvr/annotate/font.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "font_support.h"
#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

/// The box of the pixels with any alpha; empty when none.
TextBox inkedPixels(const Image& image) {
    TextBox box{image.width, image.height, 0, 0};
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            if (image.at(x, y).w > 0.f) {
                box.x0 = std::min(box.x0, x), box.x1 = std::max(box.x1, x + 1);
                box.y0 = std::min(box.y0, y), box.y1 = std::max(box.y1, y + 1);
            }
    return box;
}

TEST(LegendFont, FontconfigFindsDejaVuSans) {
    UVR_REQUIRE_FONT();
    EXPECT_EQ(font.familyName(), "DejaVu Sans") << font.path();
    const FontMetrics m = font.metrics(20.f);
    EXPECT_GT(m.ascender, 14.f);
    EXPECT_LT(m.ascender, 20.f);
    EXPECT_GT(m.descender, 3.f);
    EXPECT_GE(m.lineHeight, m.ascender + m.descender - 1.f);
}

TEST(LegendFont, TextInksOnlyItsBoxAboveAndBelowTheBaseline) {
    UVR_REQUIRE_FONT();
    Image image(200, 80);
    const int x = 20, baseline = 50;
    const int advance = font.draw(image, "Hg 0.5", 20.f, x, baseline, {1.f, 0.f, 0.f});
    EXPECT_EQ(advance, font.advance("Hg 0.5", 20.f));
    const TextBox ink = inkedPixels(image), box = font.inkBox("Hg 0.5", 20.f);
    ASSERT_FALSE(ink.empty());
    // The inked pixels are exactly inkBox's, moved to the pen origin.
    EXPECT_EQ(ink.x0, x + box.x0);
    EXPECT_EQ(ink.x1, x + box.x1);
    EXPECT_EQ(ink.y0, baseline + box.y0);
    EXPECT_EQ(ink.y1, baseline + box.y1);
    // And lie within the pen box: from the origin to the advance, from the ascender to the
    // descender ('H' reaches the cap height, 'g' descends below the baseline).
    const FontMetrics m = font.metrics(20.f);
    EXPECT_GE(ink.x0, x);
    EXPECT_LE(ink.x1, x + advance + 1);
    EXPECT_GE(ink.y0, baseline - static_cast<int>(std::ceil(m.ascender)));
    EXPECT_LE(ink.y0, baseline - 13);  // cap height of DejaVu Sans: 0.73 em
    EXPECT_GT(ink.y1, baseline + 2);
    EXPECT_LE(ink.y1, baseline + static_cast<int>(std::ceil(m.descender)) + 1);
    // Anti-aliased: edges have partial coverage; the colour is premultiplied red.
    int partial = 0, full = 0;
    for (const Vec4f& p : image.pixels) {
        EXPECT_FLOAT_EQ(p.y, 0.f);
        EXPECT_FLOAT_EQ(p.x, p.w);
        partial += p.w > 0.f && p.w < 1.f;
        full += p.w == 1.f;
    }
    EXPECT_GT(partial, 20);
    EXPECT_GT(full, 20);
}

TEST(LegendFont, AdvanceGrowsWithLengthAndSize) {
    UVR_REQUIRE_FONT();
    EXPECT_EQ(font.advance("", 16.f), 0);
    EXPECT_TRUE(font.inkBox("", 16.f).empty());
    EXPECT_TRUE(font.inkBox("   ", 16.f).empty());
    EXPECT_GT(font.advance("   ", 16.f), 0);
    int previous = 0;
    std::string s;
    for (char c : std::string("0.123456789e-30")) {
        s += c;
        const int a = font.advance(s, 16.f);
        EXPECT_GT(a, previous) << s;
        previous = a;
    }
    const int small = font.advance("density", 10.f), large = font.advance("density", 40.f);
    EXPECT_NEAR(large, 4 * small, 0.15 * large);
    // Kerning never widens a pair (DejaVu Sans kerns "AV" when its face has a kerning table).
    EXPECT_LE(font.advance("AV", 40.f), font.advance("A", 40.f) + font.advance("V", 40.f));
}

TEST(LegendFont, AnyBytesDrawWithoutCrashing) {
    UVR_REQUIRE_FONT();
    Image image(64, 32);
    const std::string replacement = "\xEF\xBF\xBD";  // U+FFFD
    EXPECT_EQ(font.advance("\xFF\xFE", 12.f), font.advance(replacement + replacement, 12.f));
    EXPECT_EQ(font.advance("a\nb", 12.f), font.advance("a" + replacement + "b", 12.f));
    for (const std::string& s : {std::string("\xC3"), std::string("\xED\xA0\x80 x"),
                                 std::string("a\0b", 3), std::string("\xF4\x90\x80\x80"),
                                 std::string("\xE4\xB8\xAD\xE6\x96\x87 \xCE\xB1\xCE\xB2")})
        EXPECT_GT(font.draw(image, s, 12.f, -5, 40, {1.f, 1.f, 1.f}), 0) << s.size();
    // Text far outside the image is clipped, not written past the pixels.
    font.draw(image, "outside", 30.f, 1000, -1000, {1.f, 1.f, 1.f});
    font.draw(image, "outside", 30.f, -1000, 1000, {1.f, 1.f, 1.f});
}

TEST(LegendFont, BadFilesAndSizesAreClearErrors) {
    UVR_REQUIRE_FONT();
    const std::string dir = testing::scratchDir();
    try {
        Font missing(dir + "/missing.ttf");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_NE(std::string(e.what()).find("missing.ttf"), std::string::npos) << e.what();
    }
    EXPECT_THROW(Font(testing::writeFile(dir + "/text.ttf", "not a font at all")), Error);
    EXPECT_THROW(font.advance("x", 0.f), Error);
    EXPECT_THROW(font.advance("x", std::nanf("")), Error);
    EXPECT_THROW(font.advance("x", 1e6f), Error);
}

TEST(LegendFont, NoFontThroughFontconfigNamesThePackage) {
    if (!textEngineAvailable()) GTEST_SKIP() << "built without text";
    // A fontconfig configuration without font folders: nothing can match.
    const std::string dir = testing::scratchDir();
    const std::string conf = testing::writeFile(
        dir + "/fonts.conf", "<?xml version=\"1.0\"?>\n<fontconfig>\n<cachedir>" + dir +
                                 "/cache</cachedir>\n</fontconfig>\n");
    const char* old = std::getenv("FONTCONFIG_FILE");
    const std::string saved = old ? old : "";
    setenv("FONTCONFIG_FILE", conf.c_str(), 1);
    try {
        findFontFile();
        ADD_FAILURE() << "a font was found without font folders";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
        EXPECT_NE(std::string(e.what()).find("fonts-dejavu-core"), std::string::npos) << e.what();
    }
    if (old)
        setenv("FONTCONFIG_FILE", saved.c_str(), 1);
    else
        unsetenv("FONTCONFIG_FILE");
    EXPECT_NO_THROW(findFontFile());
}

}  // namespace
}  // namespace uvr

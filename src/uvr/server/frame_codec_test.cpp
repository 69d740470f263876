// SPDX-License-Identifier: MIT
#include "uvr/server/frame_codec.h"

#include <gtest/gtest.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "uvr/core/error.h"

namespace uvr::server {
namespace {

TEST(FrameCodec, JpegDecodesToTheImageOverItsBackground) {
    // A smooth premultiplied gradient, half transparent: JPEG keeps it within a few levels.
    Image img(64, 48);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const float a = 0.5f;
            img.at(x, y) = Vec4f(a * x / 63.f, a * y / 47.f, a * 0.25f, a);
        }
    const Vec3f bg(0.f, 0.f, 0.4f);
    const std::vector<std::uint8_t> jpeg = encodeJpeg(img, bg, 95);
    ASSERT_GT(jpeg.size(), 2u);
    EXPECT_EQ(jpeg[0], 0xFF);
    EXPECT_EQ(jpeg[1], 0xD8);  // SOI
    tjhandle d = tjInitDecompress();
    int w = 0, h = 0, sub = 0, space = 0;
    ASSERT_EQ(tjDecompressHeader3(d, jpeg.data(), jpeg.size(), &w, &h, &sub, &space), 0);
    EXPECT_EQ(w, 64);
    EXPECT_EQ(h, 48);
    std::vector<std::uint8_t> rgb(std::size_t(w) * h * 3);
    ASSERT_EQ(tjDecompress2(d, jpeg.data(), jpeg.size(), rgb.data(), w, 0, h, TJPF_RGB, 0), 0);
    tjDestroy(d);
    double worst = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t want[3];
            compositeToRgb8(img.at(x, y), bg, want);
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::fabs(double(rgb[3 * (y * w + x) + c]) - want[c]));
        }
    EXPECT_LE(worst, 6.0);
}

/// The RGB pixels libturbojpeg decodes from a JPEG, and its size.
std::vector<std::uint8_t> decodeJpeg(const std::vector<std::uint8_t>& jpeg, int& w, int& h) {
    tjhandle d = tjInitDecompress();
    int sub = 0, space = 0;
    std::vector<std::uint8_t> rgb;
    if (tjDecompressHeader3(d, jpeg.data(), jpeg.size(), &w, &h, &sub, &space) == 0) {
        rgb.resize(std::size_t(w) * h * 3);
        if (tjDecompress2(d, jpeg.data(), jpeg.size(), rgb.data(), w, 0, h, TJPF_RGB, 0) != 0)
            rgb.clear();
    }
    tjDestroy(d);
    return rgb;
}

TEST(FrameCodec, AJpegEncodedInStripsDecodesAsTheOnePieceEncoding) {
    // Detail in every block (rings and noise), half transparent, rows not a multiple of 16.
    for (const auto& [width, height] : {std::pair{1024, 1000}, std::pair{301, 77}}) {
        Image img(width, height);
        std::uint32_t noise = 12345;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                noise = noise * 1664525u + 1013904223u;
                const float r = std::sqrt(float(x * x + y * y)) * 0.05f;
                const float a = 0.3f + 0.6f * float(noise >> 24) / 255.f;
                img.at(x, y) = Vec4f(a * (0.5f + 0.5f * std::sin(r)), a * float(y) / float(height),
                                     a * float(noise >> 28) / 15.f, a);
            }
        const Vec3f bg(0.1f, 0.2f, 0.3f);
        const std::vector<std::uint8_t> whole = encodeJpeg(img, bg, 80, 1 << 20);
        int w0 = 0, h0 = 0;
        const std::vector<std::uint8_t> want = decodeJpeg(whole, w0, h0);
        ASSERT_EQ(want.size(), std::size_t(width) * height * 3);
        for (const int rows : {0, 16, 40, 128}) {
            SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height) + ", strips of " +
                         std::to_string(rows));
            const std::vector<std::uint8_t> striped = encodeJpeg(img, bg, 80, rows);
            int w = 0, h = 0;
            const std::vector<std::uint8_t> got = decodeJpeg(striped, w, h);
            EXPECT_EQ(w, width);
            EXPECT_EQ(h, height);
            ASSERT_EQ(got.size(), want.size());
            EXPECT_TRUE(got == want);
            // Strips of fewer rows than the image: restart markers, one stream of one image.
            const bool split = (rows ? rows / 16 * 16 : kJpegStripRows) < height;
            const std::uint8_t dri[] = {0xff, 0xdd};
            EXPECT_EQ(std::search(striped.begin(), striped.end(), dri, dri + 2) != striped.end(),
                      split);
            if (!split) {
                EXPECT_TRUE(striped == whole);
            }
        }
    }
}

TEST(FrameCodec, BadQualityAndEmptyImagesAreRefused) {
    Image img(4, 4);
    EXPECT_THROW(encodeJpeg(img, Vec3f(0.f), 0), Error);
    EXPECT_THROW(encodeJpeg(img, Vec3f(0.f), 101), Error);
    EXPECT_THROW(encodeJpeg(Image(), Vec3f(0.f), 80), Error);
}

}  // namespace
}  // namespace uvr::server

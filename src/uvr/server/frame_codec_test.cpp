// SPDX-License-Identifier: MIT
#include "uvr/server/frame_codec.h"

#include <gtest/gtest.h>
#include <turbojpeg.h>

#include <cmath>

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

TEST(FrameCodec, BadQualityAndEmptyImagesAreRefused) {
    Image img(4, 4);
    EXPECT_THROW(encodeJpeg(img, Vec3f(0.f), 0), Error);
    EXPECT_THROW(encodeJpeg(img, Vec3f(0.f), 101), Error);
    EXPECT_THROW(encodeJpeg(Image(), Vec3f(0.f), 80), Error);
}

}  // namespace
}  // namespace uvr::server

// SPDX-License-Identifier: MIT
#include "uvr/render/image.h"

#include <gmock/gmock.h>
#include <png.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;
using uvr::testing::pythonHas;
using uvr::testing::runCommand;
using uvr::testing::scratchDir;
using uvr::testing::systemPython;
using uvr::testing::writeFile;

/// One 8-bit quantisation step.
constexpr float kStep = 1.f / 255.f;

void expectPixel(Vec4f got, Vec4f want, float tol, const std::string& what) {
    EXPECT_NEAR(got.x, want.x, tol) << what;
    EXPECT_NEAR(got.y, want.y, tol) << what;
    EXPECT_NEAR(got.z, want.z, tol) << what;
    EXPECT_NEAR(got.w, want.w, tol) << what;
}

/// Writes a PNG with libpng directly (independent of writePng): rows of raw samples, 16-bit
/// samples big-endian as PNG stores them, with an optional palette and transparency.
void writeRawPng(const std::string& path, int w, int h, int colorType, int depth,
                 const std::vector<std::uint8_t>& data, const std::vector<png_color>& palette = {},
                 const std::vector<std::uint8_t>& trns = {}) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png_create_info_struct(png);
    if (setjmp(png_jmpbuf(png))) {
        ADD_FAILURE() << "libpng failed writing the test image";
        png_destroy_write_struct(&png, &info);
        std::fclose(f);
        return;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, w, h, depth, colorType, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (!palette.empty()) png_set_PLTE(png, info, palette.data(), static_cast<int>(palette.size()));
    if (!trns.empty()) png_set_tRNS(png, info, trns.data(), static_cast<int>(trns.size()), nullptr);
    png_write_info(png, info);
    size_t rowBytes = data.size() / h;
    for (int y = 0; y < h; ++y)
        png_write_row(png, const_cast<png_bytep>(&data[static_cast<size_t>(y) * rowBytes]));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
}

TEST(Png, RoundTripWithinOneStep) {
    std::string path = scratchDir() + "/round.png";
    Image img(7, 5);
    for (int y = 0; y < img.height; ++y) {
        for (int x = 0; x < img.width; ++x) {
            float a = static_cast<float>((37 * x + 11 * y) % 256) / 255.f;
            Vec3f straight(x / 6.f, y / 4.f, 0.3f + 0.1f * ((x + y) % 5));
            img.at(x, y) = Vec4f(straight.x * a, straight.y * a, straight.z * a, a);
        }
    }
    writePng(path, img);
    Image back = readPng(path);
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            expectPixel(back.at(x, y), img.at(x, y), kStep,
                        std::to_string(x) + "," + std::to_string(y));
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(Png, EncodedInMemoryAsTheFileIsAtEveryLevel) {
    Image img(9, 4);
    for (int i = 0; i < 36; ++i) img.pixels[i] = Vec4f(i / 70.f, 0.2f, 0.1f, 0.5f + i / 80.f);
    const std::string path = scratchDir() + "/mem.png";
    writePng(path, img, Vec3f(0.f, 0.f, 1.f));
    const std::vector<char> file = readFileBytes(path);
    const std::vector<std::uint8_t> mem = encodePng(img, Vec3f(0.f, 0.f, 1.f));
    EXPECT_EQ(std::string(mem.begin(), mem.end()), std::string(file.begin(), file.end()));
    for (int level : {0, 1, 9}) {
        const std::vector<std::uint8_t> bytes = encodePng(img, std::nullopt, level);
        const std::string p = scratchDir() + "/level" + std::to_string(level) + ".png";
        std::ofstream(p, std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        const Image back = readPng(p);
        for (int i = 0; i < 36; ++i)
            expectPixel(back.pixels[i], img.pixels[i], kStep, std::to_string(i));
    }
    EXPECT_THROW(encodePng(img, std::nullopt, 10), Error);
    EXPECT_THROW(encodePng(Image(), std::nullopt), Error);
}

TEST(Png, LevelOneInStripsDecodesAsLibpngsEncoding) {
    // Rows past one strip (and not a multiple of it), noise and gradients, varying opacity.
    Image img(301, 2 * kPngStripRows + 37);
    std::uint32_t noise = 7;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            noise = noise * 1664525u + 1013904223u;
            const float a = float((x + y) % 7 == 0 ? 0 : noise >> 24) / 255.f;
            img.at(x, y) = Vec4f(a * x / 300.f, a * float(noise >> 28) / 15.f, a * 0.5f, a);
        }
    for (const std::optional<Vec3f> background :
         {std::optional<Vec3f>(), std::optional<Vec3f>(Vec3f(0.1f, 0.9f, 0.3f))}) {
        SCOPED_TRACE(background ? "over a background" : "with alpha");
        const auto decoded = [&](const std::vector<std::uint8_t>& bytes, const char* name) {
            const std::string p = scratchDir() + "/" + name + ".png";
            std::ofstream(p, std::ios::binary)
                .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
            return readPng(p);  // libpng: the CRCs and the zlib stream's Adler-32 are checked
        };
        const Image strips = decoded(encodePng(img, background, 1), "strips");
        const Image whole = decoded(encodePng(img, background, 6), "whole");
        ASSERT_EQ(strips.width, img.width);
        ASSERT_EQ(strips.height, img.height);
        EXPECT_TRUE(testing::sameBytes(strips.pixels, whole.pixels));
    }
}

TEST(Png, CompositesOverBackgroundAndClamps) {
    std::string path = scratchDir() + "/bg.png";
    Image img(4, 1);
    img.at(0, 0) = Vec4f(0.25f, 0.f, 0.f, 0.5f);  // half-transparent red over blue
    img.at(1, 0) = Vec4f(0.f, 0.f, 0.f, 0.f);     // empty: the background
    img.at(2, 0) = Vec4f(2.f, -1.f, std::nanf(""), 1.f);
    img.at(3, 0) = Vec4f(0.2f, 0.4f, 0.6f, 1.f);
    writePng(path, img, Vec3f(0.f, 0.f, 1.f));
    Image back = readPng(path);
    ASSERT_EQ(back.width, 4);
    expectPixel(back.at(0, 0), {64 / 255.f, 0.f, 128 / 255.f, 1.f}, 1e-6f, "over blue");
    expectPixel(back.at(1, 0), {0.f, 0.f, 1.f, 1.f}, 1e-6f, "background");
    expectPixel(back.at(2, 0), {1.f, 0.f, 0.f, 1.f}, 1e-6f, "clamped, NaN to 0");
    expectPixel(back.at(3, 0), {51 / 255.f, 102 / 255.f, 153 / 255.f, 1.f}, 1e-6f, "rounded");
}

TEST(Png, WrittenFileReadsBackInVtk) {
    if (!pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk";
    std::string dir = scratchDir();
    Image img(3, 2);
    img.at(0, 0) = Vec4f(1.f, 0.f, 0.f, 1.f);
    img.at(2, 0) = Vec4f(0.1f, 0.2f, 0.3f, 0.5f);  // straight (0.2, 0.4, 0.6) at half alpha
    img.at(1, 1) = Vec4f(0.f, 1.f, 0.f, 1.f);
    writePng(dir + "/vtk.png", img);
    std::string script = writeFile(dir + "/read.py", R"(
import sys, vtk
r = vtk.vtkPNGReader()
r.SetFileName(sys.argv[1])
r.Update()
d = r.GetOutput()
print(*d.GetDimensions(), d.GetNumberOfScalarComponents())
for y in (1, 0):  # VTK stores the bottom row first
    for x in range(3):
        print(*[int(d.GetScalarComponentAsDouble(x, y, 0, c)) for c in range(4)])
)");
    ASSERT_EQ(runCommand(std::string(systemPython()) + " " + script + " " + dir + "/vtk.png > " +
                         dir + "/out.txt 2>/dev/null"),
              0);
    std::ifstream in(dir + "/out.txt");
    std::vector<int> v;
    int k;
    while (in >> k) v.push_back(k);
    std::vector<int> want = {3,   2, 1, 4,                                       // dimensions
                             255, 0, 0, 255, 0, 0,   0, 0,   51, 102, 153, 128,  // top row
                             0,   0, 0, 0,   0, 255, 0, 255, 0,  0,   0,   0};   // bottom row
    EXPECT_EQ(v, want);
}

TEST(Png, ReadsGreyPaletteAnd16BitFiles) {
    std::string dir = scratchDir();
    // 8-bit grey, 2 x 1.
    writeRawPng(dir + "/grey.png", 2, 1, PNG_COLOR_TYPE_GRAY, 8, {0, 200});
    Image g = readPng(dir + "/grey.png");
    ASSERT_EQ(g.width, 2);
    expectPixel(g.at(1, 0), {200 / 255.f, 200 / 255.f, 200 / 255.f, 1.f}, 1e-6f, "grey");
    // 16-bit grey + alpha: value 0x8000 at alpha 0xffff, value 0xffff at alpha 0x4000.
    writeRawPng(dir + "/ga16.png", 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 16,
                {0x80, 0x00, 0xff, 0xff, 0xff, 0xff, 0x40, 0x00});
    Image ga = readPng(dir + "/ga16.png");
    float half = 0x8000 / 65535.f, quarter = 0x4000 / 65535.f;
    expectPixel(ga.at(0, 0), {half, half, half, 1.f}, 1e-6f, "16-bit grey");
    expectPixel(ga.at(1, 0), {quarter, quarter, quarter, quarter}, 1e-6f, "premultiplied");
    // 4-bit palette with transparency on entry 1, 3 x 1 pixels: entries 0, 1, 2.
    std::vector<png_color> palette = {{255, 0, 0}, {0, 255, 0}, {10, 20, 30}};
    writeRawPng(dir + "/palette.png", 3, 1, PNG_COLOR_TYPE_PALETTE, 4, {0x01, 0x20}, palette,
                {255, 51});
    Image p = readPng(dir + "/palette.png");
    ASSERT_EQ(p.width, 3);
    expectPixel(p.at(0, 0), {1.f, 0.f, 0.f, 1.f}, 1e-6f, "palette entry 0");
    expectPixel(p.at(1, 0), {0.f, 0.2f, 0.f, 0.2f}, 1e-6f, "palette entry 1, alpha 51");
    expectPixel(p.at(2, 0), {10 / 255.f, 20 / 255.f, 30 / 255.f, 1.f}, 1e-6f, "palette entry 2");
}

TEST(Png, ReadsRgb16) {
    std::string dir = scratchDir();
    writeRawPng(dir + "/rgb16.png", 1, 1, PNG_COLOR_TYPE_RGB, 16,
                {0xff, 0xff, 0x00, 0x00, 0x12, 0x34});
    expectPixel(readPng(dir + "/rgb16.png").at(0, 0), {1.f, 0.f, 0x1234 / 65535.f, 1.f}, 1e-6f,
                "16-bit RGB");
}

TEST(Png, MalformedFilesNameTheFile) {
    std::string dir = scratchDir();
    Image img(16, 16);
    for (Vec4f& p : img.pixels) p = Vec4f(0.3f, 0.6f, 0.9f, 1.f);
    img.at(3, 7) = Vec4f(0.f, 0.f, 0.f, 0.f);
    std::string good = dir + "/good.png";
    writePng(good, img);
    std::vector<char> bytes = readFileBytes(good);

    std::string truncated =
        writeFile(dir + "/truncated.png", std::string(bytes.data(), bytes.size() - 30));
    Error e = catchError([&] { readPng(truncated); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(truncated + ": byte "));

    std::string header = writeFile(dir + "/header.png", std::string(bytes.data(), 20));
    e = catchError([&] { readPng(header); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(header + ": byte "));
    EXPECT_THAT(e.what(), HasSubstr("header"));

    std::string corrupt(bytes.data(), bytes.size());
    corrupt[40] ^= 0x5a;  // inside the IDAT chunk: its CRC no longer matches
    std::string bad = writeFile(dir + "/corrupt.png", corrupt);
    e = catchError([&] { readPng(bad); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(bad + ": byte "));

    std::string text = writeFile(dir + "/text.png", "# vtk DataFile Version 3.0\n");
    e = catchError([&] { readPng(text); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(text + ": byte 0: expected the PNG signature"));

    std::string empty = writeFile(dir + "/empty.png", "");
    EXPECT_EQ(catchError([&] { readPng(empty); }).kind(), ErrorKind::Parse);

    e = catchError([&] { readPng(dir + "/absent.png"); });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_THAT(e.what(), HasSubstr("absent.png"));
}

TEST(Png, AbsurdDimensionsAreRefusedBeforeAllocating) {
    std::string dir = scratchDir();
    // A valid header claiming 1,000,000 x 1,000,000 pixels, followed by nothing.
    writeRawPng(dir + "/small.png", 1, 1, PNG_COLOR_TYPE_GRAY, 8, {7});
    std::vector<char> bytes = readFileBytes(dir + "/small.png");
    std::string huge(bytes.data(), bytes.size());
    const unsigned char dims[8] = {0x00, 0x0f, 0x42, 0x40, 0x00, 0x0f, 0x42, 0x40};
    huge.replace(16, 8, reinterpret_cast<const char*>(dims), 8);
    // Recompute the IHDR CRC (over type and data, bytes 12..28) so only the size is absurd.
    std::uint32_t crc =
        static_cast<std::uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(huge.data() + 12), 17));
    for (int i = 0; i < 4; ++i) huge[29 + i] = static_cast<char>(crc >> (24 - 8 * i));
    std::string path = writeFile(dir + "/huge.png", huge);
    Error e = catchError([&] { readPng(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Resource) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(path + ": "));
}

TEST(Png, WritingIntoMissingFolderThrowsAndLeavesNoFile) {
    std::string dir = scratchDir();
    std::string path = dir + "/no/such/folder/out.png";
    Image img(2, 2);
    Error e = catchError([&] { writePng(path, img); });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_THAT(e.what(), HasSubstr(path));
    EXPECT_FALSE(std::filesystem::exists(dir + "/no"));
    EXPECT_TRUE(std::filesystem::is_empty(dir));
    EXPECT_EQ(catchError([&] { writePng(dir + "/zero.png", Image(0, 3)); }).kind(),
              ErrorKind::Argument);
    EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(Apng, FramesAreCountedAndSizedAndTheFirstIsAPlainPng) {
    const std::string dir = testing::scratchDir();
    Image a(8, 6), b(8, 6);
    for (Vec4f& p : a.pixels) p = Vec4f(1.f, 0.f, 0.f, 1.f);
    for (Vec4f& p : b.pixels) p = Vec4f(0.f, 0.f, 1.f, 1.f);
    {
        OutputFile out(dir + "/m.png");
        ApngWriter movie(out, 2, 5.0);
        movie.add(a);
        EXPECT_THROW(movie.finish(), Error);          // one frame short
        EXPECT_THROW(movie.add(Image(4, 4)), Error);  // another size
        movie.add(b);
        EXPECT_THROW(movie.add(a), Error);  // past the count
        movie.finish();
        out.finish();
        out.commit();
    }
    // A plain PNG reader sees the first frame; the animation's chunks are there, in order.
    const Image first = readPng(dir + "/m.png");
    EXPECT_EQ(first.width, 8);
    EXPECT_EQ(first.at(3, 3).x, 1.f);
    const std::string bytes = testing::readFile(dir + "/m.png");
    const std::size_t actl = bytes.find("acTL"), idat = bytes.find("IDAT"),
                      fdat = bytes.find("fdAT");
    ASSERT_NE(actl, std::string::npos);
    ASSERT_NE(fdat, std::string::npos);
    EXPECT_LT(actl, idat);
    EXPECT_LT(idat, fdat);
    EXPECT_EQ(static_cast<unsigned char>(bytes[actl + 7]), 2u);  // num_frames 2
    EXPECT_EQ(bytes.substr(bytes.size() - 8, 4), "IEND");
    OutputFile other(dir + "/n.png");
    EXPECT_THROW(ApngWriter(other, 0, 5.0), Error);
    EXPECT_THROW(ApngWriter(other, 1, 0.0), Error);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
// SSIM/PSNR and the difference percentile against scikit-image 0.19 and numpy
// (tests/tools/ssim_reference.py) and analytic values; the seam and speckle measures on synthetic
// images and on a real render; toRgb8 against writePng; the `uvr compare` command.
#include "uvr/render/image_metrics.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

/// An 8-bit RGB image whose values are fn(x, y, channel) clamped to 0..255.
Rgb8Image makeImage(int w, int h, const std::function<double(int, int, int)>& fn) {
    Rgb8Image img;
    img.width = w;
    img.height = h;
    img.rgb.resize(static_cast<size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const double v = std::clamp(std::round(fn(x, y, c)), 0.0, 255.0);
                img.rgb[(static_cast<size_t>(y) * w + x) * 3 + c] = static_cast<std::uint8_t>(v);
            }
    return img;
}

std::uint8_t value(const Rgb8Image& img, int x, int y, int c) {
    x = std::clamp(x, 0, img.width - 1);
    y = std::clamp(y, 0, img.height - 1);
    return img.rgb[(static_cast<size_t>(y) * img.width + x) * 3 + c];
}

/// Writes an Rgb8Image as an opaque RGB PNG through writePng.
void writeRgb8(const std::string& path, const Rgb8Image& img) {
    Image out(img.width, img.height);
    for (size_t i = 0; i < out.pixels.size(); ++i)
        out.pixels[i] = Vec4f(img.rgb[i * 3] / 255.f, img.rgb[i * 3 + 1] / 255.f,
                              img.rgb[i * 3 + 2] / 255.f, 1.f);
    writePng(path, out, Vec3f(0.f, 0.f, 0.f));
}

/// A textured test image: smooth colour gradients plus a checker pattern and a disc.
Rgb8Image texture(int w, int h) {
    return makeImage(w, h, [&](int x, int y, int c) {
        const double gx = static_cast<double>(x) / w, gy = static_cast<double>(y) / h;
        const double checker = ((x / 6 + y / 6) % 2) * 40.0;
        const double disc = std::hypot(x - w * 0.6, y - h * 0.4) < h * 0.25 ? 60.0 : 0.0;
        return 30 + 150 * (c == 0 ? gx : c == 1 ? gy : 1 - gx * gy) + checker + disc;
    });
}

/// Runs the skimage oracle on pairs of PNG files; one JSON object per pair.
std::vector<nlohmann::json> skimageReference(const std::vector<std::string>& files,
                                             const std::string& dir) {
    const std::string out = dir + "/reference.json";
    std::string cmd =
        std::string(testing::systemPython()) + " " + testing::testTool("ssim_reference.py");
    for (const std::string& f : files) cmd += " " + f;
    EXPECT_EQ(testing::runCommand(cmd + " >" + out), 0) << cmd;
    std::vector<nlohmann::json> results;
    std::ifstream in(out);
    for (std::string line; std::getline(in, line);) results.push_back(nlohmann::json::parse(line));
    return results;
}

TEST(ImageMetrics, MatchesScikitImage) {
    if (!testing::pythonHas("skimage") || !testing::pythonHas("PIL"))
        GTEST_SKIP() << "system Python lacks scikit-image or Pillow";
    const std::string dir = testing::scratchDir();
    const int w = 97, h = 64;  // odd, non-square: catches transposed or off-by-one windows
    const Rgb8Image base = texture(w, h);
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> noise(-25, 25), small(-2, 2), any(0, 255);

    struct Pair {
        std::string name;
        Rgb8Image a, b;
    };
    std::vector<Pair> pairs;
    pairs.push_back({"noise", base, makeImage(w, h, [&](int x, int y, int c) {
                         return value(base, x, y, c) + noise(rng);
                     })});
    pairs.push_back({"blur", base, makeImage(w, h, [&](int x, int y, int c) {
                         int sum = 0;
                         for (int dy = -1; dy <= 1; ++dy)
                             for (int dx = -1; dx <= 1; ++dx) sum += value(base, x + dx, y + dy, c);
                         return sum / 9.0;
                     })});
    pairs.push_back({"shift", base, makeImage(w, h, [&](int x, int y, int c) {
                         return value(base, x - 2, y + 1, c);
                     })});
    pairs.push_back({"brightness", base, makeImage(w, h, [&](int x, int y, int c) {
                         return value(base, x, y, c) + 30;
                     })});
    pairs.push_back({"identical", base, base});
    // A render-like image: a dark background with a soft glowing blob, and the same with
    // low-amplitude sampling noise inside the blob.
    const Rgb8Image render = makeImage(w, h, [&](int x, int y, int c) {
        const double r = std::hypot(x - w * 0.45, y - h * 0.55) / (h * 0.4);
        const double glow = std::exp(-3 * r * r);
        return 20 + glow * (c == 0 ? 230 : c == 1 ? 160 * glow : 60 * glow * glow);
    });
    pairs.push_back({"render", render, makeImage(w, h, [&](int x, int y, int c) {
                         const int v = value(render, x, y, c);
                         return v > 25 ? v + small(rng) : v;
                     })});
    pairs.push_back({"unrelated", makeImage(w, h, [&](int, int, int) { return any(rng); }),
                     makeImage(w, h, [&](int, int, int) { return any(rng); })});

    // A real uvr render from the docs, against itself with sampling-like noise and shifted.
    const std::string demo = testing::testTool("../../docs/images/demo.png");
    if (std::filesystem::exists(demo)) {
        const Rgb8Image r = toRgb8(readPng(demo));
        pairs.push_back({"demo_noise", r, makeImage(r.width, r.height, [&](int x, int y, int c) {
                             return value(r, x, y, c) + small(rng) * 2;
                         })});
        pairs.push_back({"demo_shift", r, makeImage(r.width, r.height, [&](int x, int y, int c) {
                             return value(r, x + 1, y, c);
                         })});
    } else {
        ADD_FAILURE() << "missing " << demo;
    }

    std::vector<std::string> files;
    for (const Pair& p : pairs) {
        files.push_back(dir + "/" + p.name + "_a.png");
        files.push_back(dir + "/" + p.name + "_b.png");
        writeRgb8(files[files.size() - 2], p.a);
        writeRgb8(files.back(), p.b);
    }
    const std::vector<nlohmann::json> refs = skimageReference(files, dir);
    ASSERT_EQ(refs.size(), pairs.size());
    for (size_t i = 0; i < pairs.size(); ++i) {
        SCOPED_TRACE(pairs[i].name);
        const nlohmann::json& ref = refs[i];
        // Compare what uvr reads from the same files that skimage reads.
        const ImageComparison ours =
            compareImages(toRgb8(readPng(files[2 * i])), toRgb8(readPng(files[2 * i + 1])));
        EXPECT_NEAR(ours.ssim, ref["ssim"].get<double>(), 1e-4);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(ours.ssimChannel[c], ref["ssim_channels"][c].get<double>(), 1e-4) << c;
        if (ref["psnr"].is_null()) {
            EXPECT_TRUE(std::isinf(ours.psnr));
        } else {
            EXPECT_NEAR(ours.psnr, ref["psnr"].get<double>(), 1e-4);
        }
        EXPECT_NEAR(ours.p999Difference, ref["p999"].get<double>(), 1e-9);
        EXPECT_EQ(ours.maxAbsDifference, ref["max"].get<double>());
        EXPECT_NEAR(ours.fractionOff, ref["fraction_off"].get<double>(), 1e-12);
    }
}

TEST(ImageMetrics, AnalyticValues) {
    // Identical images: SSIM 1, PSNR infinite.
    const Rgb8Image t = texture(40, 30);
    const ImageComparison same = compareImages(t, t);
    EXPECT_DOUBLE_EQ(same.ssim, 1.0);
    EXPECT_TRUE(std::isinf(same.psnr));
    EXPECT_EQ(same.maxAbsDifference, 0.0);

    // Constant images 100 and 110: zero variances, so SSIM is the luminance term alone,
    // (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1), and MSE is 100.
    const Rgb8Image a = makeImage(20, 20, [](int, int, int) { return 100; });
    const Rgb8Image b = makeImage(20, 20, [](int, int, int) { return 110; });
    const ImageComparison r = compareImages(a, b);
    const double c1 = (0.01 * 255) * (0.01 * 255);
    const double expected = (2 * 100.0 * 110.0 + c1) / (100.0 * 100.0 + 110.0 * 110.0 + c1);
    EXPECT_NEAR(r.ssim, expected, 1e-12);
    for (double s : r.ssimChannel) EXPECT_NEAR(s, expected, 1e-12);
    EXPECT_NEAR(r.psnr, 10 * std::log10(255.0 * 255.0 / 100.0), 1e-12);
    EXPECT_EQ(r.maxAbsDifference, 10.0);

    // Only the green channel differs: R and B SSIM stay 1.
    const Rgb8Image g = makeImage(20, 20, [](int, int, int c) { return c == 1 ? 110 : 100; });
    const ImageComparison rg = compareImages(a, g);
    EXPECT_DOUBLE_EQ(rg.ssimChannel[0], 1.0);
    EXPECT_NEAR(rg.ssimChannel[1], expected, 1e-12);
    EXPECT_DOUBLE_EQ(rg.ssimChannel[2], 1.0);
}

TEST(ImageMetrics, BadSizesAreArgumentErrors) {
    auto expectArgumentError = [](const Rgb8Image& a, const Rgb8Image& b, const char* text) {
        try {
            compareImages(a, b);
            ADD_FAILURE() << "no error for " << text;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            EXPECT_THAT(e.what(), HasSubstr(text));
        }
    };
    const auto flat = [](int, int, int) { return 50; };
    expectArgumentError(makeImage(20, 20, flat), makeImage(21, 20, flat),
                        "20x20 image with a 21x20");
    expectArgumentError(makeImage(10, 30, flat), makeImage(10, 30, flat), "10x30");
    expectArgumentError(makeImage(30, 10, flat), makeImage(30, 10, flat), "at least 11x11");
    Rgb8Image broken = makeImage(20, 20, flat);
    broken.rgb.pop_back();
    expectArgumentError(broken, makeImage(20, 20, flat), "1199 RGB values");
    // The smallest valid size works.
    EXPECT_NO_THROW(compareImages(makeImage(11, 11, flat), makeImage(11, 11, flat)));
}

TEST(ImageMetrics, ToRgb8QuantisesLikeWritePng) {
    const std::string dir = testing::scratchDir();
    Image img(37, 23);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-0.2f, 1.3f);
    for (Vec4f& p : img.pixels) {
        const float a = std::clamp(u(rng), 0.f, 1.f);
        p = Vec4f(u(rng) * a, u(rng) * a, u(rng) * a, a);  // premultiplied, some out of range
    }
    img.pixels[0] = Vec4f(NAN, 0.5f, 2.f, 0.5f);
    img.pixels[1] = Vec4f(0.2f, 0.2f, 0.2f, NAN);
    const Vec3f bg(0.1f, 0.5f, 0.9f);
    const std::string path = dir + "/over.png";
    writePng(path, img, bg);
    const Rgb8Image ours = toRgb8(img, bg);
    const Rgb8Image fromFile = toRgb8(readPng(path));
    ASSERT_EQ(ours.width, 37);
    ASSERT_EQ(ours.height, 23);
    EXPECT_EQ(ours.rgb, fromFile.rgb);
    // Fully transparent pixels become the background, quantised.
    Image clear(1, 1);
    const Rgb8Image c = toRgb8(clear, bg);
    EXPECT_EQ(c.rgb, (std::vector<std::uint8_t>{26, 128, 230}));

    Image bad(4, 4);
    bad.pixels.pop_back();
    EXPECT_THROW(toRgb8(bad), Error);
}

// ---- Per-pixel measures: percentile, maximum, pixels off, seams, speckle ----

/// A smooth, non-trivial reference: gentle colour gradients (about 0.2 to 0.8 levels a pixel).
Rgb8Image smoothReference(int w, int h) {
    return makeImage(w, h, [&](int x, int y, int c) {
        return 40 + (c == 0 ? 0.8 * x : c == 1 ? 0.5 * y : 0.2 * (x + y));
    });
}

TEST(ImageMetrics, PercentileMaximumAndPixelsOffHaveKnownValues) {
    // 100x100 pixels, 12 of them off by 1..12 levels (one channel each, far apart): sorted, the
    // differences are 0 (9988 times) then 1..12 at ranks 9988..9999. numpy's 99.9th percentile
    // sits at rank 0.999 * 9999 = 9989.001: 2 + 0.001 * (3 - 2).
    const Rgb8Image a = smoothReference(100, 100);
    Rgb8Image b = a;
    for (int k = 1; k <= 12; ++k) {
        const size_t pixel = static_cast<size_t>(8 * k) * 100 + 7 * k;
        b.rgb[pixel * 3 + k % 3] = static_cast<std::uint8_t>(a.rgb[pixel * 3 + k % 3] + k);
    }
    const ImageComparison r = compareImages(a, b);
    EXPECT_NEAR(r.p999Difference, 2.001, 1e-9);
    EXPECT_EQ(r.maxAbsDifference, 12.0);
    EXPECT_NEAR(r.fractionOff, 8 / 10000.0, 1e-12);  // 5..12 exceed 4 levels

    // Every pixel off by 6 in one channel: percentile and maximum 6, all pixels off, no seam
    // (a uniform offset has no edge) and no speckle.
    const Rgb8Image c = makeImage(
        100, 100, [&](int x, int y, int ch) { return value(a, x, y, ch) + (ch == 1 ? 6 : 0); });
    const ImageComparison u = compareImages(a, c);
    EXPECT_DOUBLE_EQ(u.p999Difference, 6.0);
    EXPECT_EQ(u.maxAbsDifference, 6.0);
    EXPECT_DOUBLE_EQ(u.fractionOff, 1.0);
    EXPECT_EQ(u.seamCount, 0);
    EXPECT_EQ(u.speckleFraction, 0.0);

    const ImageComparison same = compareImages(a, a);
    EXPECT_EQ(same.p999Difference, 0.0);
    EXPECT_EQ(same.fractionOff, 0.0);
    EXPECT_EQ(same.seamCount, 0);
    EXPECT_EQ(same.seamPixels, 0);
    EXPECT_EQ(same.longestSeam, 0);
    EXPECT_EQ(same.speckleFraction, 0.0);
}

TEST(ImageMetrics, SeamDetectorFindsStepsAlongLines) {
    const int w = 160, h = 128;
    const Rgb8Image a = smoothReference(w, h);
    struct Case {
        std::string name;
        std::function<bool(int, int)> beyond;  // the side of the line that steps
        int length;                            // the seam's length in pixels
    };
    // Each line runs from border to border (edges at the border itself are not judged).
    for (const Case& c :
         std::vector<Case>{{"vertical", [](int x, int) { return x >= 70; }, h},
                           {"horizontal", [](int, int y) { return y >= 60; }, w},
                           {"slanted", [](int x, int y) { return 2 * x >= 100 + y; }, h},
                           {"diagonal", [](int x, int y) { return x - 20 >= y; }, h}}) {
        for (int step : {-3, 2, 12}) {
            SCOPED_TRACE(c.name + " step " + std::to_string(step));
            const Rgb8Image b = makeImage(w, h, [&](int x, int y, int ch) {
                return value(a, x, y, ch) + (ch == 2 && c.beyond(x, y) ? step : 0);
            });
            const ImageComparison r = compareImages(a, b);
            EXPECT_GE(r.seamCount, 1);
            EXPECT_GE(r.longestSeam, c.length - 4);
            EXPECT_LE(r.longestSeam, c.length);
            EXPECT_LE(r.seamPixels, 2 * c.length);
            EXPECT_EQ(r.speckleFraction, 0.0);
        }
    }

    // A step of one level is below kSeamMinStep.
    const Rgb8Image faint = makeImage(
        w, h, [&](int x, int y, int ch) { return value(a, x, y, ch) + (x >= 70 ? 1 : 0); });
    EXPECT_EQ(compareImages(a, faint).seamCount, 0);

    // A seam whose step fades from 8 levels to nothing along the line is one seam while the
    // step rounds to at least kSeamMinStep: 8 - 0.1 y >= 1.5, rows 0..65.
    const Rgb8Image fade = makeImage(w, h, [&](int x, int y, int ch) {
        return value(a, x, y, ch) + (ch == 0 && x >= 80 ? std::max(0.0, 8.0 - y * 0.1) : 0.0);
    });
    const ImageComparison f = compareImages(a, fade);
    EXPECT_EQ(f.seamCount, 1);
    EXPECT_GE(f.longestSeam, 64);
    EXPECT_LE(f.longestSeam, 68);

    // A square patch of side kSeamMinLength - 2: its edges are too short to be seams.
    const int side = kSeamMinLength - 2;
    const Rgb8Image patch = makeImage(w, h, [&](int x, int y, int ch) {
        return value(a, x, y, ch) + (x >= 70 && x < 70 + side && y >= 50 && y < 50 + side ? 9 : 0);
    });
    EXPECT_EQ(compareImages(a, patch).seamCount, 0);
}

TEST(ImageMetrics, SeamDetectorIgnoresGradientsNoiseAndThePicturesOwnEdges) {
    const int w = 160, h = 128;
    const Rgb8Image a = smoothReference(w, h);
    std::mt19937 rng(29);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    struct Case {
        std::string name;
        Rgb8Image reference, b;
    };
    std::vector<Case> cases;
    // Smooth differences, however steep: ramps of 0.5 and 3 levels a pixel, a smooth bump.
    for (double slope : {0.5, 3.0})
        cases.push_back({"ramp", a, makeImage(w, h, [&](int x, int y, int c) {
                             return value(a, x, y, c) - slope * (x + 0.3 * y) / 4;
                         })});
    cases.push_back({"bump", a, makeImage(w, h, [&](int x, int y, int c) {
                         return value(a, x, y, c) +
                                40 * std::exp(-(std::pow(x - 80, 2) + std::pow(y - 64, 2)) / 400);
                     })});
    // Noise of small and large amplitude, and salt-and-pepper.
    for (double sigma : {1.0, 3.0, 20.0})
        cases.push_back({"noise", a, makeImage(w, h, [&](int x, int y, int c) {
                             return value(a, x, y, c) + sigma * gauss(rng);
                         })});
    cases.push_back({"salt and pepper", a, makeImage(w, h, [&](int x, int y, int c) {
                         const double u = uniform(rng);
                         return u < 0.05 ? 0.0 : u > 0.95 ? 255.0 : value(a, x, y, c);
                     })});
    // The picture's own edges: a disc whose edge moves by a pixel or loses contrast in B.
    auto disc = [&](double radius, double contrast) {
        return makeImage(w, h, [=](int x, int y, int c) {
            return 30 + 0.3 * x + (std::hypot(x - 80, y - 64) < radius ? contrast : 0) + c;
        });
    };
    const Rgb8Image d = disc(40, 120);
    cases.push_back({"edge moved", d, disc(41, 120)});
    cases.push_back({"edge contrast", d, disc(40, 100)});
    const Rgb8Image square = makeImage(w, h, [&](int x, int y, int) {
        return x >= 40 && x < 120 && y >= 30 && y < 100 ? 200 : 20;
    });
    cases.push_back({"square moved", square, makeImage(w, h, [&](int x, int y, int c) {
                         return value(square, x - 1, y, c);
                     })});
    cases.push_back({"square contrast", square, makeImage(w, h, [&](int x, int y, int c) {
                         return value(square, x, y, c) == 200 ? 170 : 20;
                     })});
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const ImageComparison r = compareImages(c.reference, c.b);
        EXPECT_EQ(r.seamCount, 0);
        EXPECT_EQ(r.seamPixels, 0);
    }
}

TEST(ImageMetrics, SpeckleMeasureCountsIsolatedPixels) {
    const int w = 200, h = 150;
    const Rgb8Image a = smoothReference(w, h);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::uniform_int_distribution<int> small(-1, 1);
    // Salt and pepper on 1% of the pixels (a whole pixel black or white), on a render-like
    // difference: a smooth offset with +-1 level of sampling noise.
    int salted = 0;
    const Rgb8Image clean = makeImage(
        w, h, [&](int x, int y, int c) { return value(a, x, y, c) + 3 + small(rng) + 0.02 * x; });
    Rgb8Image salt = clean;
    for (int y = 1; y + 1 < h; ++y) {
        for (int x = 1; x + 1 < w; ++x) {
            if (uniform(rng) >= 0.01) continue;
            ++salted;
            const std::uint8_t v = uniform(rng) < 0.5 ? 0 : 255;
            for (int c = 0; c < 3; ++c) salt.rgb[(static_cast<size_t>(y) * w + x) * 3 + c] = v;
        }
    }
    const ImageComparison noisy = compareImages(a, salt);
    // A salted pixel next to another one may keep its 3x3 median; almost all are counted.
    EXPECT_GE(noisy.speckleFraction, 0.9 * salted / (w * h));
    EXPECT_LE(noisy.speckleFraction, 1.0 * salted / (w * h));
    EXPECT_EQ(compareImages(a, clean).speckleFraction, 0.0);

    // A texture of the picture itself (a fine checker in A) shifted by a pixel in B is not
    // speckle: the reference is not smooth there.
    const Rgb8Image checker =
        makeImage(w, h, [](int x, int y, int) { return (x + y) % 2 ? 180 : 60; });
    const Rgb8Image shifted =
        makeImage(w, h, [&](int x, int y, int c) { return value(checker, x + 1, y, c); });
    EXPECT_EQ(compareImages(checker, shifted).speckleFraction, 0.0);
}

TEST(ImageMetrics, DifferenceImageMarksSeamsAndSpeckle) {
    const int w = 64, h = 64;
    const Rgb8Image a = smoothReference(w, h);
    const Rgb8Image b = makeImage(w, h, [&](int x, int y, int c) {
        return value(a, x, y, c) + (x >= 32 ? 5 : 0) + (x == 10 && y == 10 ? 60 : 0);
    });
    const Rgb8Image d = differenceImage(a, b);
    ASSERT_EQ(d.width, w);
    ASSERT_EQ(d.height, h);
    auto px = [&](int x, int y) {
        const std::uint8_t* p = &d.rgb[(static_cast<size_t>(y) * w + x) * 3];
        return std::vector<int>{p[0], p[1], p[2]};
    };
    EXPECT_EQ(px(31, 30), (std::vector<int>{255, 0, 0}));    // the seam, marked at its left pixel
    EXPECT_EQ(px(10, 10), (std::vector<int>{255, 255, 0}));  // the odd pixel
    EXPECT_EQ(px(50, 30), (std::vector<int>{40, 40, 40}));   // 8 * 5 levels
    EXPECT_EQ(px(5, 30), (std::vector<int>{0, 0, 0}));
}

/// Renders the cylinder of ../shared/data with `uvr render` at 512x512, the view of issue 29.
Rgb8Image renderCylinder(const std::string& dir, const std::string& name, const std::string& flags);

TEST(ImageMetrics, SeamDetectorSeesAKnownPartitionSeamOnTheCylinder) {
    if (!testing::haveSharedData()) GTEST_SKIP() << "no ../shared/data";
    const std::string dir = testing::scratchDir();
    // The exact integrator is the truth; the reference marcher (one step everywhere) is smooth.
    // Morrical et al.'s configuration (the variance rule, point samples) with a step bound
    // longer than the cylinder takes long steps in the partitions of small colour variance and
    // short ones elsewhere: a step in brightness at a partition boundary, halfway along the
    // cylinder, across its whole height. (The default and the pre-integrated variance rule
    // showed it too until long steps ended at the mesh's boundary, issue 29.)
    const Rgb8Image exact = renderCylinder(dir, "exact", "--method exact");
    const Rgb8Image reference = renderCylinder(dir, "reference", "--method reference");
    const Rgb8Image seam = renderCylinder(
        dir, "variance", "--sampling point --step-rule variance --max-sample-distance 1");
    const ImageComparison withSeam = compareImages(exact, seam);
    EXPECT_GE(withSeam.seamCount, 1);
    EXPECT_GE(withSeam.longestSeam, kSeamMinLength);
    const ImageComparison smooth = compareImages(exact, reference);
    EXPECT_EQ(smooth.seamCount, 0);
    EXPECT_EQ(smooth.seamPixels, 0);

    // Among the marked pixels, a vertical line halfway along the cylinder: seam pixels in at
    // least 30 rows of the columns around the middle (the rest mark the top and bottom edges of
    // the brighter half).
    const Rgb8Image marks = differenceImage(exact, seam);
    int rows = 0;
    for (int y = 0; y < marks.height; ++y) {
        bool marked = false;
        for (int x = marks.width / 2 - 8; x <= marks.width / 2 + 8; ++x)
            marked = marked || (value(marks, x, y, 0) == 255 && value(marks, x, y, 1) == 0);
        rows += marked;
    }
    EXPECT_GE(rows, 30);
}

Rgb8Image renderCylinder(const std::string& dir, const std::string& name,
                         const std::string& flags) {
    const std::string out = dir + "/" + name + ".png";
    const std::string cmd = testing::uvrBinary() + " render -q " +
                            testing::sharedData("cylinder_quadratic_as_tets.vtk") +
                            " --field pressure --azimuth 90 --tf Viridis --size 512x512 " + flags +
                            " -o " + out;
    EXPECT_EQ(testing::runCommand(cmd), 0) << cmd;
    return toRgb8(readPng(out));
}

// ---- `uvr compare` ----

struct UvrRun {
    int code = -1;
    std::string out, err;
};

UvrRun runUvr(const std::string& args, const std::string& dir) {
    UvrRun r;
    r.code = testing::runCommand(testing::uvrBinary() + " " + args + " >" + dir + "/out.txt 2>" +
                                 dir + "/err.txt");
    r.out = testing::readFile(dir + "/out.txt");
    r.err = testing::readFile(dir + "/err.txt");
    return r;
}

TEST(ImageMetrics, CompareCommandPrintsTheMetrics) {
    const std::string dir = testing::scratchDir();
    const Rgb8Image a = texture(64, 48);
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> noise(-15, 15);
    const Rgb8Image b =
        makeImage(64, 48, [&](int x, int y, int c) { return value(a, x, y, c) + noise(rng); });
    const std::string fa = dir + "/a.png", fb = dir + "/b.png";
    writeRgb8(fa, a);
    writeRgb8(fb, b);
    const ImageComparison expected = compareImages(a, b);
    ASSERT_LT(expected.ssim, 0.99);
    ASSERT_GT(expected.ssim, 0.3);

    // Text output: the SSIM line, rounded to 6 decimals.
    const UvrRun text = runUvr("compare -q " + fa + " " + fb, dir);
    ASSERT_EQ(text.code, 0) << text.err;
    double ssim = -2, psnr = -1;
    ASSERT_EQ(std::sscanf(text.out.c_str(), "SSIM %lf  PSNR %lf dB", &ssim, &psnr), 2) << text.out;
    EXPECT_NEAR(ssim, expected.ssim, 5e-7);
    EXPECT_NEAR(psnr, expected.psnr, 5e-3);
    EXPECT_THAT(text.out, HasSubstr("SSIM per channel  R "));

    // JSON output: full precision.
    const UvrRun json = runUvr("compare -q --json " + fa + " " + fb, dir);
    ASSERT_EQ(json.code, 0) << json.err;
    const nlohmann::json j = nlohmann::json::parse(json.out);
    EXPECT_NEAR(j["ssim"].get<double>(), expected.ssim, 1e-12);
    EXPECT_NEAR(j["ssim_channels"][1].get<double>(), expected.ssimChannel[1], 1e-12);
    EXPECT_NEAR(j["psnr"].get<double>(), expected.psnr, 1e-9);
    EXPECT_FALSE(j["identical"].get<bool>());

    // Identical files: PSNR is null in JSON, "inf" in text.
    const UvrRun same = runUvr("compare -q --json " + fa + " " + fa, dir);
    ASSERT_EQ(same.code, 0) << same.err;
    EXPECT_TRUE(nlohmann::json::parse(same.out)["psnr"].is_null());
    EXPECT_THAT(runUvr("compare " + fa + " " + fa, dir).out, HasSubstr("PSNR inf dB"));

    // --min-ssim: 1 below the threshold, 0 at or above it.
    const UvrRun below = runUvr("compare -q --min-ssim 0.99 " + fa + " " + fb, dir);
    EXPECT_EQ(below.code, 1) << below.out << below.err;
    EXPECT_THAT(below.out, HasSubstr("FAIL"));
    EXPECT_EQ(runUvr("compare -q --min-ssim 0.2 " + fa + " " + fb, dir).code, 0);
    const UvrRun jsonBelow = runUvr("compare -q --json --min-ssim 0.99 " + fa + " " + fb, dir);
    EXPECT_EQ(jsonBelow.code, 1);
    EXPECT_FALSE(nlohmann::json::parse(jsonBelow.out)["pass"].get<bool>());
}

TEST(ImageMetrics, CompareCommandReportsThePerPixelMeasuresAndTheirThresholds) {
    const std::string dir = testing::scratchDir();
    const Rgb8Image a = smoothReference(96, 80);
    // A step of 6 levels in green right of column 48: one seam 80 pixels long.
    const Rgb8Image b = makeImage(96, 80, [&](int x, int y, int c) {
        return value(a, x, y, c) + (c == 1 && x >= 48 ? 6 : 0);
    });
    const std::string fa = dir + "/a.png", fb = dir + "/b.png";
    writeRgb8(fa, a);
    writeRgb8(fb, b);
    const ImageComparison expected = compareImages(a, b);
    ASSERT_EQ(expected.seamCount, 1);
    ASSERT_EQ(expected.longestSeam, 80);

    const UvrRun json = runUvr("compare -q --json " + fa + " " + fb, dir);
    ASSERT_EQ(json.code, 0) << json.err;
    const nlohmann::json j = nlohmann::json::parse(json.out);
    for (const ComparisonField& f : differenceFields(expected)) {
        ASSERT_TRUE(j.contains(f.name)) << f.name;
        EXPECT_DOUBLE_EQ(j[f.name].get<double>(), f.value) << f.name;
    }
    EXPECT_EQ(j["seam_count"].get<int>(), 1);
    EXPECT_EQ(j["longest_seam"].get<int>(), 80);
    EXPECT_FALSE(j.contains("pass"));
    const UvrRun text = runUvr("compare -q " + fa + " " + fb, dir);
    EXPECT_THAT(text.out, HasSubstr(differenceSummary(expected)));
    EXPECT_THAT(text.out, HasSubstr("1 seam (80 pixels, longest 80)"));

    // Thresholds: each fails alone; the JSON says which values were asked for.
    struct Case {
        std::string flags;
        int code;
    };
    for (const Case& c : std::vector<Case>{{"--no-seams", 1},
                                           {"--max-diff 5", 1},
                                           {"--max-diff 6", 0},
                                           {"--max-p999 6", 0},
                                           {"--max-p999 5.5", 1},
                                           {"--min-ssim 0.5 --max-diff 6", 0},
                                           {"--min-ssim 0.5 --max-diff 6 --no-seams", 1}}) {
        const UvrRun r = runUvr("compare -q " + c.flags + " " + fa + " " + fb, dir);
        EXPECT_EQ(r.code, c.code) << c.flags << "\n" << r.out << r.err;
        EXPECT_THAT(r.out, HasSubstr(c.code ? "FAIL: " : "pass: ")) << c.flags;
        const UvrRun rj = runUvr("compare -q --json " + c.flags + " " + fa + " " + fb, dir);
        EXPECT_EQ(rj.code, c.code) << c.flags;
        EXPECT_EQ(nlohmann::json::parse(rj.out)["pass"].get<bool>(), c.code == 0) << c.flags;
    }
    // Same images: no seam, --no-seams passes.
    EXPECT_EQ(runUvr("compare -q --no-seams --max-diff 0 " + fa + " " + fa, dir).code, 0);

    // --diff-image: 8 x the difference in grey, the seam's left pixels red.
    const std::string fd = dir + "/diff.png";
    ASSERT_EQ(runUvr("compare -q --diff-image " + fd + " " + fa + " " + fb, dir).code, 0);
    const Rgb8Image d = toRgb8(readPng(fd));
    EXPECT_EQ(d.rgb, differenceImage(a, b).rgb);
    EXPECT_EQ(value(d, 47, 40, 0), 255);
    EXPECT_EQ(value(d, 47, 40, 1), 0);
    EXPECT_EQ(value(d, 60, 40, 1), 48);
}

TEST(ImageMetrics, CompareCommandRejectsBadInputWithCode2) {
    const std::string dir = testing::scratchDir();
    const std::string fa = dir + "/a.png", fsmall = dir + "/small.png", ftiny = dir + "/tiny.png";
    writeRgb8(fa, texture(64, 48));
    writeRgb8(fsmall, texture(48, 64));
    writeRgb8(ftiny, texture(8, 8));
    const std::string notPng = testing::writeFile(dir + "/text.png", "hello");
    struct Case {
        std::string args, needle;
    };
    for (const Case& c : std::vector<Case>{{fa + " " + dir + "/missing.png", "missing.png"},
                                           {fa + " " + fsmall, "48x64 but " + fa + " is 64x48"},
                                           {ftiny + " " + ftiny, "tiny.png: is 8x8"},
                                           {fa + " " + notPng, "text.png"},
                                           {fa + " " + fa + " --min-ssim nan", "--min-ssim"},
                                           {fa + " " + fa + " --max-p999 -1", "--max-p999"},
                                           {fa + " " + fa + " --max-diff 300", "--max-diff"},
                                           {fa + " " + fa + " --background 2,0,0", "--background"},
                                           {fa, "B"}}) {
        const UvrRun r = runUvr("compare -q " + c.args, dir);
        EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
        EXPECT_EQ(testing::lineCount(r.err), 1) << c.args << "\n" << r.err;
        EXPECT_THAT(r.err, HasSubstr(c.needle)) << c.args;
        EXPECT_TRUE(r.out.empty()) << r.out;
    }
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/tf/transfer_function.h"

#include <gmock/gmock.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;
using uvr::testing::expectVec;
using uvr::testing::pythonHas;
using uvr::testing::runCommand;
using uvr::testing::runPython;
using uvr::testing::scratchDir;
using uvr::testing::systemPython;
using uvr::testing::writeFile;

/// Tolerance for colours compared against VTK's and matplotlib's own evaluation.
constexpr float kColorTol = 5e-4f;

/// Runs the function and returns the uvr::Error it throws (fails the test if none).

/// Runs a Python script with the system Python and returns its stdout parsed as numbers.

TransferFunction twoPoint(ColorSpace space, Vec3f a, Vec3f b) {
    TransferFunction tf;
    tf.colorSpace = space;
    tf.colors = {{0.f, a}, {1.f, b}};
    tf.opacities = {{0.f, 0.f}, {1.f, 1.f}};
    return tf;
}

TEST(TransferFunction, RgbInterpolationIsLinearAndClamped) {
    TransferFunction tf;
    tf.colors = {{0.f, {0.f, 0.f, 0.f}}, {0.25f, {1.f, 0.f, 0.f}}, {1.f, {1.f, 1.f, 0.5f}}};
    tf.opacities = {{0.f, 0.f}, {1.f, 1.f}};
    expectVec(tf.colorAt(0.125f), {0.5f, 0.f, 0.f}, 1e-6f, "middle of first segment");
    expectVec(tf.colorAt(0.625f), {1.f, 0.5f, 0.25f}, 1e-6f, "middle of second segment");
    expectVec(tf.colorAt(-3.f), {0.f, 0.f, 0.f}, 0.f, "clamped below");
    expectVec(tf.colorAt(7.f), {1.f, 1.f, 0.5f}, 0.f, "clamped above");
    expectVec(tf.colorAt(0.25f), {1.f, 0.f, 0.f}, 0.f, "at a control point");
}

TEST(TransferFunction, OpacityIsPiecewiseLinearWithJumps) {
    TransferFunction tf = twoPoint(ColorSpace::RGB, Vec3f(0.f), Vec3f(1.f));
    tf.opacities = {{0.2f, 0.1f}, {0.6f, 0.5f}, {0.6f, 0.9f}, {1.f, 0.7f}};
    EXPECT_FLOAT_EQ(tf.opacityAt(0.f), 0.1f);
    EXPECT_FLOAT_EQ(tf.opacityAt(0.4f), 0.3f);
    EXPECT_FLOAT_EQ(tf.opacityAt(0.5999f), 0.4999f);
    EXPECT_FLOAT_EQ(tf.opacityAt(0.6f), 0.9f);  // a jump takes the upper value at its position
    EXPECT_FLOAT_EQ(tf.opacityAt(0.8f), 0.8f);
    EXPECT_FLOAT_EQ(tf.opacityAt(2.f), 0.7f);
}

TEST(TransferFunction, BakeSamplesEvenlyIncludingEnds) {
    TransferFunction tf = transferFunctionPreset("grayscale");
    std::vector<Vec4f> table = tf.bake(5);
    ASSERT_EQ(table.size(), 5u);
    for (int k = 0; k < 5; ++k) {
        float t = k / 4.f;
        EXPECT_FLOAT_EQ(table[k].x, t);
        EXPECT_FLOAT_EQ(table[k].y, t);
        EXPECT_FLOAT_EQ(table[k].z, t);
        EXPECT_FLOAT_EQ(table[k].w, t);
    }
    EXPECT_EQ(catchError([&] { tf.bake(1); }).kind(), ErrorKind::Argument);
}

TEST(TransferFunction, LogScaleBakesTheLogPositionOfEachValue) {
    // Entry k of a table over [1, 1000] holds value v_k = 1 + 999 k / (n - 1) and gets the
    // function at log10(v_k) / 3 (ParaView's volume mappers: a table linear in the value).
    TransferFunction tf = transferFunctionPreset("grayscale");
    tf.logScale = true;
    const int n = 2001;
    const std::vector<Vec4f> table = tf.bakeOverRange(n, 1.0, 1000.0);
    ASSERT_EQ(table.size(), size_t(n));
    for (int k = 0; k < n; k += 50) {
        const double t = std::log10(1.0 + 999.0 * k / (n - 1)) / 3.0;
        EXPECT_NEAR(table[k].x, t, 1e-6) << k;
        EXPECT_NEAR(table[k].w, t, 1e-6) << k;
    }
    EXPECT_FLOAT_EQ(table.back().x, 1.f);
    // Linear without logScale: the same as bake.
    tf.logScale = false;
    EXPECT_FLOAT_EQ(tf.bakeOverRange(5, 1.0, 1000.0)[1].x, 0.25f);
    tf.logScale = true;
    EXPECT_EQ(catchError([&] { tf.bakeOverRange(8, 0.0, 10.0); }).kind(), ErrorKind::Argument);

    // Table size: the first step from lo spans 1 / 1023 of the log range, as a linear table's.
    const int size = logTableSize(1024, 1.0, 1000.0);
    const double first = 999.0 / (size - 1);
    EXPECT_LE(std::log10(1.0 + first) / 3.0, 1.0 / 1023 * 1.0001);
    EXPECT_GT(std::log10(1.0 + 999.0 / (size - 2)) / 3.0, 1.0 / 1023 * 0.999);
    EXPECT_LE(logTableSize(1024, 1.0, 1.001), 1025);  // narrow ranges need hardly more
    EXPECT_LT(logTableSize(1024, 1.0, 1.5), 1300);
    EXPECT_EQ(logTableSize(1024, 1.0, 1e8), kMaxLogTableSize);
    EXPECT_EQ(logTableResolvedFrom(size, 1024, 1.0, 1000.0), 1.0);
    const double from = logTableResolvedFrom(kMaxLogTableSize, 1024, 1.0, 1e8);
    EXPECT_GT(from, 1.0);
    EXPECT_LT(from, 1e8);
}

TEST(TransferFunction, LabConversionMatchesPublishedValues) {
    // sRGB primaries in CIE L*a*b* (D65), e.g. from Bruce Lindbloom's calculator.
    Vec3f red = srgbToLab({1.f, 0.f, 0.f});
    EXPECT_NEAR(red.x, 53.24f, 0.05f);
    EXPECT_NEAR(red.y, 80.09f, 0.1f);
    EXPECT_NEAR(red.z, 67.20f, 0.1f);
    Vec3f white = srgbToLab({1.f, 1.f, 1.f});
    EXPECT_NEAR(white.x, 100.f, 0.01f);
    EXPECT_NEAR(white.y, 0.f, 0.05f);
    EXPECT_NEAR(white.z, 0.f, 0.05f);
    for (Vec3f c : {Vec3f(0.2f, 0.5f, 0.9f), Vec3f(0.01f, 0.02f, 0.f), Vec3f(0.9f, 0.3f, 0.1f)})
        expectVec(labToSrgb(srgbToLab(c)), c, 1e-4f, "Lab round trip");
}

TEST(TransferFunction, DivergingThroughWhiteBetweenSaturatedEnds) {
    // Moreland 2009: two saturated ends with hues far apart pass through an unsaturated colour
    // of magnitude max(M1, M2, 88), i.e. a neutral grey with L* = 88 for these two colours.
    TransferFunction tf =
        twoPoint(ColorSpace::Diverging, {0.230f, 0.299f, 0.754f}, {0.706f, 0.016f, 0.150f});
    Vec3f mid = tf.colorAt(0.5f);
    Vec3f grey = labToSrgb({88.f, 0.f, 0.f});
    expectVec(mid, grey, 1e-4f, "Msh midpoint");
    EXPECT_NEAR(mid.x, mid.y, 1e-4f);
    expectVec(tf.colorAt(0.f), {0.230f, 0.299f, 0.754f}, 1e-6f, "end 0");
    expectVec(tf.colorAt(1.f), {0.706f, 0.016f, 0.150f}, 1e-6f, "end 1");
}

TEST(TransferFunction, CoolToWarmAndLabMatchVtkColorTransferFunction) {
    if (!pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk";
    std::string dir = scratchDir();
    std::vector<double> v = runPython(dir, R"(
import vtk
def table(space, pts):
    f = vtk.vtkColorTransferFunction()
    getattr(f, 'SetColorSpaceTo' + space)()
    for p in pts: f.AddRGBPoint(*p)
    for i in range(101): print(*f.GetColor(i / 100.0))
table('Diverging', [(0, 0.23137254902, 0.298039215686, 0.752941176471), (0.5, 0.865, 0.865, 0.865),
                    (1, 0.705882352941, 0.0156862745098, 0.149019607843)])
table('Lab', [(0, 0, 0.6, 0.75), (0.3, 0.1, 0.1, 0.1), (1, 0.77, 0.47, 0.34)])
)");
    ASSERT_EQ(v.size(), 2u * 101 * 3);
    TransferFunction ctw = transferFunctionPreset("Cool to Warm");
    TransferFunction lab;
    lab.colorSpace = ColorSpace::Lab;
    lab.colors = {
        {0.f, {0.f, 0.6f, 0.75f}}, {0.3f, {0.1f, 0.1f, 0.1f}}, {1.f, {0.77f, 0.47f, 0.34f}}};
    for (int i = 0; i <= 100; ++i) {
        const double* d = &v[3 * i];
        const double* l = &v[3 * (101 + i)];
        expectVec(ctw.colorAt(i / 100.f), Vec3f(d[0], d[1], d[2]), kColorTol,
                  "cool-to-warm at " + std::to_string(i));
        expectVec(lab.colorAt(i / 100.f), Vec3f(l[0], l[1], l[2]), kColorTol,
                  "Lab at " + std::to_string(i));
    }
}

TEST(TransferFunction, MatplotlibPresetsMatchMatplotlib) {
    if (!pythonHas("matplotlib")) GTEST_SKIP() << "system Python has no matplotlib";
    std::string dir = scratchDir();
    const char* names[] = {"viridis", "inferno", "magma", "plasma"};
    std::vector<double> v = runPython(dir, R"(
from matplotlib import colormaps
for name in ('viridis', 'inferno', 'magma', 'plasma'):
    for c in colormaps[name].colors: print(*c)
)");
    ASSERT_EQ(v.size(), 4u * 256 * 3);
    for (int m = 0; m < 4; ++m) {
        const TransferFunction tf = transferFunctionPreset(names[m]);
        for (int i = 0; i < 256; ++i) {
            const double* c = &v[3 * (256 * m + i)];
            // ParaView's map puts entry i at i / 255; uvr keeps a subset of its points, within
            // 0.45 / 255 of the full map (presets.cpp), plus float rounding.
            expectVec(tf.colorAt(i / 255.f), Vec3f(c[0], c[1], c[2]), 0.5f / 255.f + 1e-5f,
                      tf.name + " entry " + std::to_string(i));
        }
    }
}

TEST(TransferFunction, PresetsMatchPublishedReferenceColours) {
    // 8-bit hex colours as matplotlib's documentation and the BIDS colormap repository list
    // them (entry 0, 128 = viridis(0.5), 255); Turbo's ends from Google's published table.
    struct Ref {
        const char* preset;
        int entry;  ///< of 256, at position entry / 255
        unsigned hex;
    };
    const Ref refs[] = {
        {"Viridis (matplotlib)", 0, 0x440154},
        {"viridis", 128, 0x21918c},
        {"viridis", 255, 0xfde725},
        {"Inferno (matplotlib)", 0, 0x000004},
        {"inferno", 255, 0xfcffa4},
        {"Magma (matplotlib)", 0, 0x000004},
        {"magma", 255, 0xfcfdbf},
        {"Plasma (matplotlib)", 0, 0x0d0887},
        {"plasma", 255, 0xf0f921},
        {"Turbo", 0, 0x30123b},
        {"turbo", 255, 0x7a0403},
    };
    for (const Ref& r : refs) {
        const Vec3f want((r.hex >> 16) / 255.f, ((r.hex >> 8) & 0xff) / 255.f,
                         (r.hex & 0xff) / 255.f);
        // Half an 8-bit level of rounding in the hex, half of subsampling (presets.cpp).
        expectVec(transferFunctionPreset(r.preset).colorAt(r.entry / 255.f), want, 1.f / 255.f,
                  std::string(r.preset) + " entry " + std::to_string(r.entry));
    }
}

TEST(TransferFunction, EveryPresetNameRoundTrips) {
    const std::vector<ColorMapInfo> presets = transferFunctionPresets();
    ASSERT_GE(presets.size(), 28u);
    for (const char* name : {"Cool to Warm",
                             "Cool to Warm (Extended)",
                             "Warm to Cool",
                             "Black-Body Radiation",
                             "Inferno (matplotlib)",
                             "Magma (matplotlib)",
                             "Plasma (matplotlib)",
                             "Viridis (matplotlib)",
                             "Turbo",
                             "Jet",
                             "Rainbow Uniform",
                             "Rainbow Desaturated",
                             "Blue Orange (divergent)",
                             "X Ray",
                             "Grayscale",
                             "Blue - Green - Orange",
                             "Cold and Hot",
                             "Blue to Red Rainbow",
                             "Yellow - Gray - Blue",
                             "Linear Green (Gr4L)",
                             "erdc_rainbow_bright",
                             "Spectral_lowBlue",
                             "gist_earth",
                             "Haze",
                             "Black, Blue and White"}) {
        const auto it = std::find_if(presets.begin(), presets.end(),
                                     [&](const ColorMapInfo& p) { return p.name == name; });
        EXPECT_NE(it, presets.end()) << name;
    }
    for (const ColorMapInfo& p : presets) {
        // The name itself, in other cases and with '-' or '_' for spaces.
        std::string lower, dashed, snake;
        for (char c : p.name) {
            lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            dashed += c == ' ' ? '-' : c;
            snake += c == ' ' ? '_' : c;
        }
        for (const std::string& query : {p.name, lower, dashed, snake}) {
            const TransferFunction tf = transferFunctionPreset(query);
            EXPECT_EQ(tf.name, p.name) << query;
            EXPECT_FLOAT_EQ(tf.opacityAt(0.f), 0.f) << query;
            EXPECT_FLOAT_EQ(tf.opacityAt(0.3f), 0.3f) << query;
            EXPECT_FLOAT_EQ(tf.opacityAt(1.f), 1.f) << query;
        }
        EXPECT_GE(p.points, 2) << p.name;
        // Positions span [0, 1]; HSV maps are resampled into more points.
        const TransferFunction tf = transferFunctionPreset(p.name);
        EXPECT_FLOAT_EQ(tf.colors.front().x, 0.f) << p.name;
        EXPECT_FLOAT_EQ(tf.colors.back().x, 1.f) << p.name;
        if (p.colorSpace != "HSV") {
            EXPECT_EQ(static_cast<int>(tf.colors.size()), p.points) << p.name;
        }
    }
}

TEST(TransferFunction, PresetsResolveAliasesAndSuffixes) {
    const std::pair<const char*, const char*> cases[] = {
        {"cool-to-warm", "Cool to Warm"},
        {"COOL_TO_WARM", "Cool to Warm"},
        {"cool to warm (extended)", "Cool to Warm (Extended)"},
        {"black-body", "Black-Body Radiation"},
        {"Black-Body Radiation", "Black-Body Radiation"},
        {"viridis", "Viridis (matplotlib)"},
        {"Inferno", "Inferno (matplotlib)"},
        {"grayscale", "Grayscale"},
        {"greyscale", "Grayscale"},
        {"gray", "Grayscale"},
        {"xray", "X Ray"},
        {"x-ray", "X Ray"},
        {"Blue Orange", "Blue Orange (divergent)"},
        {"linear green", "Linear Green (Gr4L)"},
        {"black blue and white", "Black, Blue and White"},
        {"rainbow-uniform", "Rainbow Uniform"},
    };
    for (const auto& [query, name] : cases) EXPECT_EQ(transferFunctionPreset(query).name, name);
    expectVec(transferFunctionPreset("X Ray").nanColor, {1.f, 0.f, 0.f}, 0.f, "X Ray NanColor");
    // ParaView applies presets without HSVWrap: blue to red through green, not magenta.
    expectVec(transferFunctionPreset("Blue to Red Rainbow").colorAt(0.5f), {0.f, 1.f, 0.f}, 1e-5f,
              "green in the middle");

    Error e = catchError([] { transferFunctionPreset("jett"); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr("\"jett\"; did you mean \"Jet\"?"));
    // A slip in the name before a parenthesis (issue 35).
    EXPECT_THAT(catchError([] { transferFunctionPreset("viridiss"); }).what(),
                HasSubstr("did you mean \"Viridis (matplotlib)\"?"));
    EXPECT_THAT(e.what(), HasSubstr("`uvr presets` lists"));
    e = catchError([] { transferFunctionPreset("rainbow"); });
    EXPECT_THAT(e.what(), HasSubstr("\"Rainbow Uniform\""));
    EXPECT_THAT(e.what(), HasSubstr("\"Rainbow Desaturated\""));
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    EXPECT_THAT(catchError([] { transferFunctionPreset("zzzzzzzzzz"); }).what(),
                ::testing::Not(HasSubstr("did you mean")));
}

TEST(TransferFunction, BlackBodyMatchesParaViewPreset) {
    // ParaView's ColorMaps.json: 0 black, 0.4 (0.902, 0, 0), 0.8 (0.902, 0.902, 0), 1 white.
    TransferFunction tf = transferFunctionPreset("black-body");
    expectVec(tf.colorAt(0.2f), {0.45098f, 0.f, 0.f}, 1e-5f, "0.2");
    expectVec(tf.colorAt(0.6f), {0.901961f, 0.45098f, 0.f}, 1e-5f, "0.6");
    expectVec(tf.colorAt(0.9f), {0.95098f, 0.95098f, 0.5f}, 1e-5f, "0.9");
}

TEST(TransferFunction, OpacitySpecs) {
    TransferFunction tf = transferFunctionPreset("viridis");
    applyOpacitySpec(tf, "ramp:0.5");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.5f), 0.25f);
    applyOpacitySpec(tf, "constant:0.2");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.f), 0.2f);
    EXPECT_FLOAT_EQ(tf.opacityAt(1.f), 0.2f);
    applyOpacitySpec(tf, "step:0.3");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.29f), 0.f);
    EXPECT_FLOAT_EQ(tf.opacityAt(0.3f), 1.f);
    applyOpacitySpec(tf, "step:0.3:0.4");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.9f), 0.4f);
    applyOpacitySpec(tf, "0:0,0.5:1,1:0");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.25f), 0.5f);
    EXPECT_FLOAT_EQ(tf.opacityAt(0.75f), 0.5f);
    applyOpacitySpec(tf, "ramp");
    EXPECT_FLOAT_EQ(tf.opacityAt(0.7f), 0.7f);

    for (const char* bad :
         {"ramp:2", "ramp:", "ramp:x", "constant", "constant:0.1:2", "step", "step:0.5:1:1",
          "step:-1", "foo", "0.5", "0:0,0.5", "0.5:1,0.2:0", "0:nan", "", "1e999:0"}) {
        Error e = catchError([&] { applyOpacitySpec(tf, bad); });
        EXPECT_EQ(e.kind(), ErrorKind::Argument) << bad;
        EXPECT_THAT(e.what(), HasSubstr(std::string(1, '"').append(bad).append(1, '"'))) << bad;
        EXPECT_THAT(e.what(), HasSubstr("step:T[:A]")) << bad;
    }
    EXPECT_FLOAT_EQ(tf.opacityAt(0.7f), 0.7f);  // a bad spec leaves the function unchanged
}

TEST(TransferFunction, LoadsParaViewExport) {
    std::string dir = scratchDir();
    // RGBPoints over data range [-10, 30]; Points with a shifted midpoint and a range beyond it.
    std::string path = writeFile(dir + "/map.json", R"([
  {
    "ColorSpace" : "Lab",
    "Name" : "My map",
    "NanColor" : [1, 1, 0],
    "RGBPoints" : [-10, 0, 0, 1,  10, 1, 1, 1,  30, 1, 0, 0],
    "Points" : [-20, 0, 0.5, 0,  10, 0.4, 0.25, 0,  30, 1, 0.5, 0]
  }
])");
    TransferFunction tf = loadParaViewColorMap(path);
    EXPECT_EQ(tf.name, "My map");
    EXPECT_EQ(tf.colorSpace, ColorSpace::Lab);
    ASSERT_TRUE(tf.sourceRange.has_value());
    EXPECT_FLOAT_EQ(tf.sourceRange->first, -10.f);
    EXPECT_FLOAT_EQ(tf.sourceRange->second, 30.f);
    ASSERT_EQ(tf.colors.size(), 3u);
    EXPECT_FLOAT_EQ(tf.colors[1].x, 0.5f);
    expectVec(tf.colorAt(0.5f), {1.f, 1.f, 1.f}, 1e-6f, "white at data value 10");
    // Opacity at data value -10 (normalised 0) on the segment from (-20, 0) to (10, 0.4).
    EXPECT_NEAR(tf.opacityAt(0.f), 0.4f / 3.f, 1e-6f);
    EXPECT_NEAR(tf.opacityAt(0.5f), 0.4f, 1e-6f);
    // Midpoint 0.25 between data 10 and 30: value 0.7 at data 15 (normalised 0.625).
    EXPECT_NEAR(tf.opacityAt(0.625f), 0.7f, 1e-6f);
    EXPECT_NEAR(tf.opacityAt(0.8125f), 0.85f, 1e-6f);
    EXPECT_NEAR(tf.opacityAt(1.f), 1.f, 1e-6f);
}

TEST(TransferFunction, ParaViewJsonExportReadsBackToTheSameMap) {
    // Every preset with a shaped opacity, linear and log, over a range that is not [0, 1]; the
    // export is parsed in memory as an upload would be.
    for (const std::string& name : transferFunctionPresetNames()) {
        for (bool log : {false, true}) {
            TransferFunction tf = transferFunctionPreset(name);
            applyOpacitySpec(tf, "0:0,0.3:0.8,0.31:0.1,1:0.5");
            tf.logScale = log;
            tf.nanColor = {0.25f, 0.5f, 0.75f};
            tf.nanOpacity = 0.125f;
            const double lo = log ? 0.01 : -3.5, hi = 420.0;
            const std::string text = paraViewColorMapJson(tf, lo, hi);
            const TransferFunction back =
                parseParaViewColorMap(std::vector<char>(text.begin(), text.end()), "upload");
            const std::string what = name + (log ? " (log)" : "");
            EXPECT_EQ(back.name, tf.name) << what;
            EXPECT_EQ(back.colorSpace, tf.colorSpace) << what;
            EXPECT_EQ(back.logScale, log) << what;
            ASSERT_TRUE(back.sourceRange) << what;
            EXPECT_FLOAT_EQ(back.sourceRange->first, float(lo)) << what;
            EXPECT_FLOAT_EQ(back.sourceRange->second, float(hi)) << what;
            expectVec(back.nanColor, tf.nanColor, 0.f, what);
            EXPECT_EQ(back.nanOpacity, tf.nanOpacity) << what;
            for (int i = 0; i <= 200; ++i) {
                const float t = i / 200.f;
                expectVec(back.colorAt(t), tf.colorAt(t), 2e-5f, what + " at " + std::to_string(t));
                EXPECT_NEAR(back.opacityAt(t), tf.opacityAt(t), 2e-5f) << what << " at " << t;
            }
        }
    }
}

TEST(TransferFunction, ParaViewJsonExportRefusesBadRangesAndUploadsNameTheirSource) {
    const TransferFunction tf = transferFunctionPreset("viridis");
    EXPECT_EQ(catchError([&] { paraViewColorMapJson(tf, 1.0, 1.0); }).kind(), ErrorKind::Argument);
    EXPECT_EQ(catchError([&] { paraViewColorMapJson(tf, 0.0, NAN); }).kind(), ErrorKind::Argument);
    TransferFunction log = tf;
    log.logScale = true;
    EXPECT_THAT(catchError([&] { paraViewColorMapJson(log, 0.0, 1.0); }).what(),
                HasSubstr("positive range"));
    const std::string bad = R"([{"Name": "x", "RGBPoints": [0, 1, 2]}])";
    const Error e = catchError([&] {
        parseParaViewColorMap({bad.begin(), bad.end()}, "the upload");
    });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("the upload"));
    EXPECT_THAT(e.what(), HasSubstr("RGBPoints"));
}

TEST(TransferFunction, ParaViewCoolToWarmExportEqualsPreset) {
    std::string dir = scratchDir();
    std::string path = writeFile(dir + "/ctw.json", R"({"ColorSpace": "Diverging",
        "Name": "Cool to Warm", "RGBPoints": [0.5, 0.23137254902, 0.298039215686, 0.752941176471,
        1.5, 0.865, 0.865, 0.865, 2.5, 0.705882352941, 0.0156862745098, 0.149019607843]})");
    TransferFunction tf = loadTransferFunction(path);
    TransferFunction preset = loadTransferFunction("cool-to-warm");
    for (int i = 0; i <= 20; ++i) {
        expectVec(tf.colorAt(i / 20.f), preset.colorAt(i / 20.f), 1e-6f, std::to_string(i));
        EXPECT_FLOAT_EQ(tf.opacityAt(i / 20.f), i / 20.f);  // no Points: a linear ramp
    }
}

TEST(TransferFunction, HsvExportIsResampledAsParaViewAppliesIt) {
    std::string dir = scratchDir();
    // ParaView applies a preset with HSVWrap off unless it says "HSVWrap": 1
    // (vtkSMTransferFunctionProxy::ApplyPreset): red to blue through green; wrapped, the
    // shorter way round through magenta.
    std::string path = writeFile(dir + "/hsv.json", R"([{"ColorSpace": "HSV",
        "RGBPoints": [0, 1, 0, 0, 1, 0, 0, 1]}])");
    TransferFunction tf = loadParaViewColorMap(path);
    EXPECT_EQ(tf.colorSpace, ColorSpace::RGB);
    expectVec(tf.colorAt(0.f), {1.f, 0.f, 0.f}, 1e-6f, "red end");
    expectVec(tf.colorAt(0.5f), {0.f, 1.f, 0.f}, 1e-5f, "green in the middle");
    expectVec(tf.colorAt(1.f), {0.f, 0.f, 1.f}, 1e-6f, "blue end");
    path = writeFile(dir + "/wrap.json", R"([{"ColorSpace": "HSV", "HSVWrap": 1,
        "RGBPoints": [0, 1, 0, 0, 1, 0, 0, 1]}])");
    expectVec(loadParaViewColorMap(path).colorAt(0.5f), {1.f, 0.f, 1.f}, 1e-5f,
              "magenta in the middle when wrapped");
}

TEST(TransferFunction, MalformedParaViewExportsNameFileAndKey) {
    std::string dir = scratchDir();
    struct Case {
        const char* name;
        std::string json;
        ErrorKind kind;
        const char* where;
        const char* what;
    };
    // 100,000 levels of nesting (a stack overflow printing the value in the message before).
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const std::string deepInKey =
        "[{\"RGBPoints\": " + std::string(100000, '[') + std::string(100000, ']') + "}]";
    const std::string utf16 = std::string("\xFF\xFE[\0{\0}\0]\0", 10);
    const Case cases[] = {
        {"deep", deep, ErrorKind::Parse, "byte 64", "JSON nested deeper than 64 levels"},
        {"deepkey", deepInKey, ErrorKind::Parse, "byte 77", "JSON nested deeper than 64 levels"},
        {"brackets",
         "[{\"Name\": \"[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\", "
         "\"RGBPoints\": [0, 1, 1, 1], \"Points\": [[0, 1, 0.5, 0], 1, 0.5, 0]}]",
         ErrorKind::Parse, "\"Points\"[0]", "finite number, got an array of 4 value(s)"},
        {"utf16", utf16, ErrorKind::Parse, "byte 0",
         "UTF-16 text is not supported; save the colour map as UTF-8"},
        {"nested", "[[1, 2]]", ErrorKind::Parse, "colour map 0",
         "expected a colour-map object, got an array of 2 value(s)"},
        {"controls", "[{\"ColorSpace\": \"a\\nb\\u0000\\u00ff\", \"RGBPoints\": [0, 1, 1, 1]}]",
         ErrorKind::Parse, "\"ColorSpace\"", "got \"a\\nb\\x00\xC3\xBF\""},
        {"badutf8", "[{\"ColorSpace\": \"\xFF\"}]", ErrorKind::Parse, "byte ", "\\xff"},
        {"notjson", "[{\"RGBPoints\": [0, 1, 1, 1,]}]", ErrorKind::Parse, "byte 28", "JSON"},
        {"empty", "[]", ErrorKind::Parse, "top level", "empty array"},
        {"scalar", "42", ErrorKind::Parse, "colour map", "colour-map object"},
        {"norgb", "[{\"Name\": \"x\", \"IndexedColors\": [1, 0, 0]}]", ErrorKind::Parse,
         "colour map 0", "\"RGBPoints\""},
        {"count", "[{\"RGBPoints\": [0, 1, 1, 1, 1, 0, 0]}]", ErrorKind::Parse,
         "colour map 0 \"RGBPoints\"", "multiple of 4"},
        {"token", "[{\"RGBPoints\": [0, 1, \"a\", 1]}]", ErrorKind::Parse, "\"RGBPoints\"[2]",
         "finite number"},
        {"order", "[{\"RGBPoints\": [0, 1, 1, 1, 2, 0, 0, 0, 1, 1, 1, 1]}]", ErrorKind::Parse,
         "\"RGBPoints\"[8]", "do not decrease"},
        {"colour", "[{\"RGBPoints\": [0, 1, 1, 1, 1, 0, 1.5, 0]}]", ErrorKind::Parse,
         "\"RGBPoints\"[6]", "colour component in [0, 1]"},
        {"opacity", "[{\"RGBPoints\": [0, 1, 1, 1], \"Points\": [0, 2, 0.5, 0]}]", ErrorKind::Parse,
         "\"Points\"[1]", "opacity in [0, 1]"},
        {"points", "[{\"RGBPoints\": [0, 1, 1, 1], \"Points\": {}}]", ErrorKind::Parse,
         "\"Points\"", "array of numbers"},
        {"space", "[{\"ColorSpace\": \"CMYK\", \"RGBPoints\": [0, 1, 1, 1]}]", ErrorKind::Parse,
         "\"ColorSpace\"", "\"CMYK\""},
        {"step", "[{\"ColorSpace\": \"Step\", \"RGBPoints\": [0, 1, 1, 1]}]",
         ErrorKind::Unsupported, "\"ColorSpace\"", "Step"},
        // Found by fuzz_colormap_json: a number beyond a double escaped as a JSON library error.
        {"overflow", "[{\"RGBPoints\": [0, 1, 1, 1e999]}]", ErrorKind::Parse, "byte 25",
         "number overflow parsing '1e999'"},
    };
    for (const Case& c : cases) {
        std::string path = writeFile(dir + "/" + c.name + ".json", c.json);
        Error e = catchError([&] { loadParaViewColorMap(path); });
        EXPECT_EQ(e.kind(), c.kind) << c.name << ": " << e.what();
        EXPECT_THAT(e.what(), HasSubstr(path + ": ")) << c.name;
        EXPECT_THAT(e.what(), HasSubstr(c.where)) << c.name;
        EXPECT_THAT(e.what(), HasSubstr(c.what)) << c.name;
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << c.name;
    }
}

TEST(TransferFunction, PresetsFilePicksMapsByName) {
    const std::string path = uvr::testing::testData("presets/several_maps.json");
    const std::vector<ColorMapInfo> maps = listParaViewColorMaps(path);
    ASSERT_EQ(maps.size(), 4u);
    EXPECT_EQ(maps[0].name, "Deep Sea");
    EXPECT_EQ(maps[0].colorSpace, "Lab");
    EXPECT_EQ(maps[0].points, 3);
    EXPECT_EQ(maps[1].colorSpace, "RGB");
    EXPECT_EQ(maps[3].colorSpace, "indexed");
    EXPECT_EQ(maps[3].points, 0);

    TransferFunction deep = loadParaViewColorMap(path, "Deep Sea");
    EXPECT_EQ(deep.name, "Deep Sea");
    EXPECT_EQ(deep.colorSpace, ColorSpace::Lab);
    expectVec(deep.nanColor, {1.f, 0.f, 1.f}, 0.f, "NanColor");
    EXPECT_EQ(deep.nanOpacity, 0.f);  // no NanOpacity: NaN stays invisible
    // Loose matching, and the same through --tf's FILE.json:NAME.
    EXPECT_EQ(loadParaViewColorMap(path, "deep-sea").name, "Deep Sea");
    const TransferFunction ember = loadTransferFunction(path + ":Ember Ramp");
    EXPECT_EQ(ember.name, "Ember Ramp");
    EXPECT_FLOAT_EQ(ember.nanOpacity, 0.5f);
    expectVec(ember.nanColor, {0.2f, 0.8f, 0.2f}, 0.f, "Ember NanColor");
    EXPECT_NEAR(ember.opacityAt(0.5f), 0.4f, 1e-6f);
    EXPECT_FALSE(ember.logScale);

    // UseLogScale: positions 1, 10, 1000 lie at log10 0, 1/3 and 1 of the range.
    const TransferFunction decades = loadTransferFunction(path + ":decades");
    EXPECT_TRUE(decades.logScale);
    ASSERT_EQ(decades.colors.size(), 3u);
    EXPECT_NEAR(decades.colors[1].x, 1.f / 3.f, 1e-6f);
    ASSERT_TRUE(decades.sourceRange.has_value());
    EXPECT_FLOAT_EQ(decades.sourceRange->second, 1000.f);

    // Without a name a file of several maps is refused, naming them.
    Error e = catchError([&] { loadTransferFunction(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(), HasSubstr(path + ": holds 4 colour maps: pick one with `tf` " + path +
                                    ":NAME, one of \"Deep Sea\", \"Ember Ramp\", \"Decades\", "
                                    "\"Site Classes\""));
    EXPECT_THAT(e.what(), HasSubstr("`uvr presets " + path + "` lists them"));
    // An unknown name: the close ones.
    e = catchError([&] { loadTransferFunction(path + ":Deep See"); });
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_THAT(e.what(),
                HasSubstr("no colour map named \"Deep See\"; did you mean \"Deep Sea\"?"));
    e = catchError([&] { loadTransferFunction(path + ":zzzzzzzz"); });
    EXPECT_THAT(e.what(), HasSubstr("; it holds \"Deep Sea\", \"Ember Ramp\""));
    // A categorical map is named but cannot be loaded.
    e = catchError([&] { loadTransferFunction(path + ":Site Classes"); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("colour map 3"));
    EXPECT_THAT(e.what(), HasSubstr("indexed (categorical)"));
    EXPECT_EQ(catchError([&] { loadTransferFunction(path + ":"); }).kind(), ErrorKind::Argument);
}

TEST(TransferFunction, PresetsFileListsTheFirstTenNames) {
    std::string json = "[";
    for (int i = 0; i < 12; ++i)
        json += std::string(i ? ", " : "") + "{\"Name\": \"Map " + std::to_string(i) +
                "\", \"RGBPoints\": [0, 0, 0, 0, 1, 1, 1, 1]}";
    const std::string path = writeFile(scratchDir() + "/twelve.json", json + "]");
    Error e = catchError([&] { loadParaViewColorMap(path); });
    EXPECT_THAT(e.what(), HasSubstr("holds 12 colour maps"));
    EXPECT_THAT(e.what(), HasSubstr("\"Map 9\" and 2 more"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("Map 10")));
    // One map in an array needs no name; a name that is not its own is refused.
    const std::string one =
        writeFile(scratchDir() + "/one.json", R"([{"Name": "Only", "RGBPoints": [0, 0, 0, 0]}])");
    EXPECT_EQ(loadTransferFunction(one).name, "Only");
    EXPECT_EQ(loadTransferFunction(one + ":only").name, "Only");
    EXPECT_THAT(catchError([&] { loadTransferFunction(one + ":Other"); }).what(),
                HasSubstr("no colour map named \"Other\""));
    // Malformed NanColor / NanOpacity name the key.
    for (const char* bad : {R"([{"RGBPoints": [0, 0, 0, 0], "NanColor": [1, 2, 0]}])",
                            R"([{"RGBPoints": [0, 0, 0, 0], "NanColor": "red"}])",
                            R"([{"RGBPoints": [0, 0, 0, 0], "NanOpacity": 3}])"}) {
        const std::string p = writeFile(scratchDir() + "/bad.json", bad);
        Error b = catchError([&] { loadParaViewColorMap(p); });
        EXPECT_EQ(b.kind(), ErrorKind::Parse) << bad;
        EXPECT_THAT(b.what(), HasSubstr("colour map 0 \"Nan")) << bad;
    }
}

TEST(TransferFunction, LoadTransferFunctionChoosesPresetOrFile) {
    EXPECT_EQ(loadTransferFunction("Viridis").name, "Viridis (matplotlib)");
    std::string missing = scratchDir() + "/missing.json";
    Error e = catchError([&] { loadTransferFunction(missing); });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_THAT(e.what(), HasSubstr(missing));
    EXPECT_EQ(catchError([] { loadTransferFunction("nope"); }).kind(), ErrorKind::Argument);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/render/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "uvr/core/error.h"

namespace uvr {

namespace {

/// The 5x7 bitmap font for ASCII 32..126: seven rows of five pixels, '#' set, rows separated by
/// spaces.
constexpr const char* kFontArt[95] = {
    "..... ..... ..... ..... ..... ..... .....",  // space
    "..#.. ..#.. ..#.. ..#.. ..#.. ..... ..#..",  // !
    ".#.#. .#.#. ..... ..... ..... ..... .....",  // "
    ".#.#. .#.#. ##### .#.#. ##### .#.#. .#.#.",  // #
    "..#.. .#### #.#.. .###. ..#.# ####. ..#..",  // $
    "##... ##..# ...#. ..#.. .#... #..## ...##",  // %
    ".##.. #..#. #.#.. .#... #.#.# #..#. .##.#",  // &
    "..#.. ..#.. .#... ..... ..... ..... .....",  // '
    "...#. ..#.. .#... .#... .#... ..#.. ...#.",  // (
    ".#... ..#.. ...#. ...#. ...#. ..#.. .#...",  // )
    "..... ..#.. #.#.# .###. #.#.# ..#.. .....",  // *
    "..... ..#.. ..#.. ##### ..#.. ..#.. .....",  // +
    "..... ..... ..... ..... .##.. ..#.. .#...",  // ,
    "..... ..... ..... ##### ..... ..... .....",  // -
    "..... ..... ..... ..... ..... .##.. .##..",  // .
    "..... ....# ...#. ..#.. .#... #.... .....",  // /
    ".###. #...# #..## #.#.# ##..# #...# .###.",  // 0
    "..#.. .##.. ..#.. ..#.. ..#.. ..#.. .###.",  // 1
    ".###. #...# ....# ...#. ..#.. .#... #####",  // 2
    "##### ...#. ..#.. ...#. ....# #...# .###.",  // 3
    "...#. ..##. .#.#. #..#. ##### ...#. ...#.",  // 4
    "##### #.... ####. ....# ....# #...# .###.",  // 5
    "..##. .#... #.... ####. #...# #...# .###.",  // 6
    "##### ....# ...#. ..#.. .#... .#... .#...",  // 7
    ".###. #...# #...# .###. #...# #...# .###.",  // 8
    ".###. #...# #...# .#### ....# ...#. .##..",  // 9
    "..... .##.. .##.. ..... .##.. .##.. .....",  // :
    "..... .##.. .##.. ..... .##.. ..#.. .#...",  // ;
    "...#. ..#.. .#... #.... .#... ..#.. ...#.",  // <
    "..... ..... ##### ..... ##### ..... .....",  // =
    ".#... ..#.. ...#. ....# ...#. ..#.. .#...",  // >
    ".###. #...# ....# ...#. ..#.. ..... ..#..",  // ?
    ".###. #...# ....# .##.# #.#.# #.#.# .###.",  // @
    ".###. #...# #...# ##### #...# #...# #...#",  // A
    "####. #...# #...# ####. #...# #...# ####.",  // B
    ".###. #...# #.... #.... #.... #...# .###.",  // C
    "###.. #..#. #...# #...# #...# #..#. ###..",  // D
    "##### #.... #.... ####. #.... #.... #####",  // E
    "##### #.... #.... ####. #.... #.... #....",  // F
    ".###. #...# #.... #.### #...# #...# .####",  // G
    "#...# #...# #...# ##### #...# #...# #...#",  // H
    ".###. ..#.. ..#.. ..#.. ..#.. ..#.. .###.",  // I
    "..### ...#. ...#. ...#. ...#. #..#. .##..",  // J
    "#...# #..#. #.#.. ##... #.#.. #..#. #...#",  // K
    "#.... #.... #.... #.... #.... #.... #####",  // L
    "#...# ##.## #.#.# #.#.# #...# #...# #...#",  // M
    "#...# #...# ##..# #.#.# #..## #...# #...#",  // N
    ".###. #...# #...# #...# #...# #...# .###.",  // O
    "####. #...# #...# ####. #.... #.... #....",  // P
    ".###. #...# #...# #...# #.#.# #..#. .##.#",  // Q
    "####. #...# #...# ####. #.#.. #..#. #...#",  // R
    ".#### #.... #.... .###. ....# ....# ####.",  // S
    "##### ..#.. ..#.. ..#.. ..#.. ..#.. ..#..",  // T
    "#...# #...# #...# #...# #...# #...# .###.",  // U
    "#...# #...# #...# #...# #...# .#.#. ..#..",  // V
    "#...# #...# #...# #.#.# #.#.# #.#.# .#.#.",  // W
    "#...# #...# .#.#. ..#.. .#.#. #...# #...#",  // X
    "#...# #...# .#.#. ..#.. ..#.. ..#.. ..#..",  // Y
    "##### ....# ...#. ..#.. .#... #.... #####",  // Z
    ".###. .#... .#... .#... .#... .#... .###.",  // [
    "..... #.... .#... ..#.. ...#. ....# .....",  // backslash
    ".###. ...#. ...#. ...#. ...#. ...#. .###.",  // ]
    "..#.. .#.#. #...# ..... ..... ..... .....",  // ^
    "..... ..... ..... ..... ..... ..... #####",  // _
    ".#... ..#.. ...#. ..... ..... ..... .....",  // `
    "..... ..... .###. ....# .#### #...# .####",  // a
    "#.... #.... #.##. ##..# #...# #...# ####.",  // b
    "..... ..... .###. #.... #.... #...# .###.",  // c
    "....# ....# .##.# #..## #...# #...# .####",  // d
    "..... ..... .###. #...# ##### #.... .###.",  // e
    "..##. .#..# .#... ###.. .#... .#... .#...",  // f
    "..... .#### #...# #...# .#### ....# .###.",  // g
    "#.... #.... #.##. ##..# #...# #...# #...#",  // h
    "..#.. ..... .##.. ..#.. ..#.. ..#.. .###.",  // i
    "...#. ..... ..##. ...#. ...#. #..#. .##..",  // j
    "#.... #.... #..#. #.#.. ##... #.#.. #..#.",  // k
    ".##.. ..#.. ..#.. ..#.. ..#.. ..#.. .###.",  // l
    "..... ..... ##.#. #.#.# #.#.# #...# #...#",  // m
    "..... ..... #.##. ##..# #...# #...# #...#",  // n
    "..... ..... .###. #...# #...# #...# .###.",  // o
    "..... ..... ####. #...# ####. #.... #....",  // p
    "..... ..... .##.# #..## .#### ....# ....#",  // q
    "..... ..... #.##. ##..# #.... #.... #....",  // r
    "..... ..... .###. #.... .###. ....# ####.",  // s
    ".#... .#... ###.. .#... .#... .#..# ..##.",  // t
    "..... ..... #...# #...# #...# #..## .##.#",  // u
    "..... ..... #...# #...# #...# .#.#. ..#..",  // v
    "..... ..... #...# #...# #.#.# #.#.# .#.#.",  // w
    "..... ..... #...# .#.#. ..#.. .#.#. #...#",  // x
    "..... ..... #...# #...# .#### ....# .###.",  // y
    "..... ..... ##### ...#. ..#.. .#... #####",  // z
    "...#. ..#.. ..#.. .#... ..#.. ..#.. ...#.",  // {
    "..#.. ..#.. ..#.. ..#.. ..#.. ..#.. ..#..",  // |
    ".#... ..#.. ..#.. ...#. ..#.. ..#.. .#...",  // }
    "..... ..... .#... #.#.# ...#. ..... .....",  // ~
};

/// One glyph as seven 5-bit rows, bit 4 the leftmost pixel.
using Glyph = std::array<std::uint8_t, kGlyphHeight>;

/// Decodes the font art at compile time; a malformed entry makes the build fail.
constexpr std::array<Glyph, 95> decodeFont() {
    std::array<Glyph, 95> font{};
    for (int g = 0; g < 95; ++g) {
        const char* art = kFontArt[g];
        for (int r = 0; r < kGlyphHeight; ++r) {
            std::uint8_t bits = 0;
            for (int c = 0; c < 5; ++c) {
                const char ch = art[r * 6 + c];
                if (ch != '#' && ch != '.') throw "font art must be '#' or '.'";
                bits = static_cast<std::uint8_t>((bits << 1) | (ch == '#' ? 1 : 0));
            }
            const char sep = art[r * 6 + 5];
            if (r + 1 < kGlyphHeight ? sep != ' ' : sep != '\0') throw "font art row length";
            font[g][r] = bits;
        }
    }
    return font;
}

constexpr std::array<Glyph, 95> kFont = decodeFont();

const Glyph& glyphFor(char ch) {
    const int code = static_cast<unsigned char>(ch);
    return kFont[(code >= 32 && code <= 126 ? code : '?') - 32];
}

void setPixel(Image& image, int x, int y, Vec3f color) {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
    image.at(x, y) = Vec4f(color.x, color.y, color.z, 1.f);
}

void fillRect(Image& image, int x0, int y0, int x1, int y1, Vec3f color) {
    for (int y = std::max(y0, 0); y <= std::min(y1, image.height - 1); ++y)
        for (int x = std::max(x0, 0); x <= std::min(x1, image.width - 1); ++x)
            image.at(x, y) = Vec4f(color.x, color.y, color.z, 1.f);
}

/// Draws text rotated 90 degrees counter-clockwise (read bottom to top); (x, y) is the bottom-left
/// corner of the first glyph.
void drawTextVertical(Image& image, int x, int y, const std::string& text, Vec3f color) {
    for (size_t i = 0; i < text.size(); ++i) {
        const Glyph& g = glyphFor(text[i]);
        for (int r = 0; r < kGlyphHeight; ++r)
            for (int c = 0; c < 5; ++c)
                if (g[r] & (0x10 >> c))
                    setPixel(image, x + r, y - static_cast<int>(i) * kGlyphAdvance - c, color);
    }
}

/// A pixel box with the pixel-centre mapping of data ranges onto it.
struct Mapping {
    const PlotFrame& frame;
    double toX(double x) const {
        return frame.left + 0.5 +
               (x - frame.x.lo) / (frame.x.hi - frame.x.lo) * (frame.right - frame.left);
    }
    double toY(double y, const AxisTicks& axis) const {
        return frame.bottom + 0.5 -
               (y - axis.lo) / (axis.hi - axis.lo) * (frame.bottom - frame.top);
    }
};

/// Plots a 2x2 pixel dot centred at continuous position (px, py), clipped to the plot area.
void plotDot(Image& image, const PlotFrame& f, double px, double py, Vec3f color) {
    const int x0 = static_cast<int>(std::floor(px - 0.5));
    const int y0 = static_cast<int>(std::floor(py - 0.5));
    for (int y = y0; y <= y0 + 1; ++y)
        for (int x = x0; x <= x0 + 1; ++x)
            if (x >= f.left && x <= f.right && y >= f.top && y <= f.bottom)
                setPixel(image, x, y, color);
}

/// A 2-pixel-wide line by digital differential analysis, sampled every half pixel.
void drawLine(Image& image, const PlotFrame& f, double x0, double y0, double x1, double y1,
              Vec3f color) {
    const double len = std::max(std::abs(x1 - x0), std::abs(y1 - y0));
    // Segments far outside the image are clipped by plotDot; cap the work for absurd data.
    const int steps = static_cast<int>(std::min(std::ceil(len * 2.0), 1e5)) + 1;
    for (int i = 0; i <= steps; ++i) {
        const double t = static_cast<double>(i) / steps;
        plotDot(image, f, x0 + t * (x1 - x0), y0 + t * (y1 - y0), color);
    }
}

/// A filled 5x5 square marker centred on the pixel containing (px, py), clipped to the area.
void drawMarker(Image& image, const PlotFrame& f, double px, double py, Vec3f color) {
    const int cx = static_cast<int>(std::floor(px)), cy = static_cast<int>(std::floor(py));
    fillRect(image, std::max(cx - 2, f.left), std::max(cy - 2, f.top), std::min(cx + 2, f.right),
             std::min(cy + 2, f.bottom), color);
}

/// Largest tick label width of an axis.
int tickLabelWidth(const AxisTicks& t) {
    int w = 0;
    for (int i = 0; i < t.count(); ++i) w = std::max(w, textWidth(formatTick(t.value(i), t.step)));
    return w;
}

/// Heckbert's nice number: 1, 2, 5 or 10 times a power of ten near x (rounded or the ceiling).
double niceNumber(double x, bool round) {
    const double exponent = std::floor(std::log10(x));
    const double power = std::pow(10.0, exponent);
    const double f = x / power;
    double nice;
    if (round)
        nice = f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10;
    else
        nice = f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10;
    return nice * power;
}

const Vec3f kBlack(0.f, 0.f, 0.f);
const Vec3f kGrid(0.88f, 0.88f, 0.88f);
const Vec3f kLegendBorder(0.6f, 0.6f, 0.6f);
constexpr int kTickLength = 4;
constexpr int kGap = 4;
constexpr int kOuterMargin = 8;
constexpr int kTitleScale = 2;
constexpr int kLegendRowHeight = 12;

}  // namespace

int AxisTicks::count() const {
    return static_cast<int>(std::llround((hi - lo) / step)) + 1;
}

double AxisTicks::value(int i) const {
    const double v = lo + i * step;
    return std::abs(v) < step * 1e-9 ? 0.0 : v;
}

AxisTicks niceTicks(double dataMin, double dataMax, int targetCount) {
    if (!std::isfinite(dataMin) || !std::isfinite(dataMax) || dataMin > dataMax) {
        dataMin = 0.0;
        dataMax = 1.0;
    }
    if (dataMin == dataMax) {
        const double pad = dataMin != 0.0 ? std::abs(dataMin) * 0.5 : 0.5;
        dataMin -= pad;
        dataMax += pad;
    }
    targetCount = std::max(targetCount, 2);
    const double range = niceNumber(dataMax - dataMin, false);
    AxisTicks t;
    t.step = niceNumber(range / (targetCount - 1), true);
    t.lo = std::floor(dataMin / t.step) * t.step;
    t.hi = std::ceil(dataMax / t.step) * t.step;
    // Ranges at the ends of double precision (overflowing widths, denormals) get [0, 1].
    const double ticks = (t.hi - t.lo) / t.step;
    if (!(t.step > 0.0) || !std::isfinite(t.lo) || !std::isfinite(t.hi) || !(ticks >= 1.0) ||
        ticks > 100.0)
        return AxisTicks{};
    return t;
}

std::string formatTick(double value, double step) {
    char buf[64];
    const double magnitude = std::max(std::abs(value), step);
    if (magnitude >= 1e6 || step < 1e-4) {
        std::snprintf(buf, sizeof buf, "%.3g", value);
    } else {
        const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
        std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    }
    return buf;
}

int textWidth(const std::string& text, int scale) {
    if (text.empty()) return 0;
    return (static_cast<int>(text.size()) * kGlyphAdvance - 1) * std::max(scale, 1);
}

void drawText(Image& image, int x, int y, const std::string& text, Vec3f color, int scale) {
    scale = std::max(scale, 1);
    for (size_t i = 0; i < text.size(); ++i) {
        const Glyph& g = glyphFor(text[i]);
        const int gx = x + static_cast<int>(i) * kGlyphAdvance * scale;
        for (int r = 0; r < kGlyphHeight; ++r)
            for (int c = 0; c < 5; ++c)
                if (g[r] & (0x10 >> c))
                    fillRect(image, gx + c * scale, y + r * scale, gx + (c + 1) * scale - 1,
                             y + (r + 1) * scale - 1, color);
    }
}

PlotFrame plotFrame(const PlotSpec& spec) {
    constexpr int kMaxSide = 16384;
    if (spec.width < 160 || spec.height < 120 || spec.width > kMaxSide || spec.height > kMaxSide) {
        throwError(ErrorKind::Argument, "",
                   "plot size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                       " is out of range; expected 160x120 to 16384x16384");
    }
    // Step 1: data ranges per axis (non-finite points are skipped).
    const double inf = std::numeric_limits<double>::infinity();
    double xMin = inf, xMax = -inf, yMin[2] = {inf, inf}, yMax[2] = {-inf, -inf};
    PlotFrame f;
    for (size_t s = 0; s < spec.series.size(); ++s) {
        const PlotSeries& series = spec.series[s];
        if (series.x.size() != series.y.size()) {
            throwError(ErrorKind::Argument, "",
                       "plot series " + std::to_string(s) + " ('" + series.label + "') has " +
                           std::to_string(series.x.size()) + " x values and " +
                           std::to_string(series.y.size()) + " y values; expected as many");
        }
        const int axis = series.rightAxis ? 1 : 0;
        f.hasRightAxis = f.hasRightAxis || series.rightAxis;
        for (size_t i = 0; i < series.x.size(); ++i) {
            if (!std::isfinite(series.x[i]) || !std::isfinite(series.y[i])) continue;
            xMin = std::min(xMin, series.x[i]);
            xMax = std::max(xMax, series.x[i]);
            yMin[axis] = std::min(yMin[axis], series.y[i]);
            yMax[axis] = std::max(yMax[axis], series.y[i]);
        }
    }
    f.x = niceTicks(xMin, xMax);
    f.y = niceTicks(yMin[0], yMax[0]);
    f.yRight = niceTicks(yMin[1], yMax[1]);

    // Step 2: margins around the plot area for the title, labels and tick numbers.
    const int labelBand = kGlyphHeight + kOuterMargin;
    f.top = kOuterMargin + (spec.title.empty() ? 4 : kGlyphHeight * kTitleScale + kOuterMargin);
    f.bottom =
        spec.height - 1 -
        (kTickLength + kGap + kGlyphHeight + kOuterMargin + (spec.xLabel.empty() ? 0 : labelBand));
    f.left = kOuterMargin + (spec.yLabel.empty() ? 0 : labelBand) + tickLabelWidth(f.y) + kGap +
             kTickLength;
    const int lastXLabel = textWidth(formatTick(f.x.value(f.x.count() - 1), f.x.step));
    if (f.hasRightAxis) {
        f.right = spec.width - 1 -
                  (kTickLength + kGap + tickLabelWidth(f.yRight) + kOuterMargin +
                   (spec.yRightLabel.empty() ? 0 : labelBand));
    } else {
        f.right = spec.width - 1 - std::max(2 * kOuterMargin, lastXLabel / 2 + kGap);
    }
    if (f.right - f.left < 40 || f.bottom - f.top < 40) {
        throwError(ErrorKind::Argument, "",
                   "plot size " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                       " leaves no room for the plot area; expected a larger plot");
    }
    return f;
}

Image renderPlot(const PlotSpec& spec) {
    const PlotFrame f = plotFrame(spec);
    const Mapping map{f};
    Image image(spec.width, spec.height);
    fillRect(image, 0, 0, spec.width - 1, spec.height - 1, Vec3f(1.f, 1.f, 1.f));

    // Step 1: grid lines, the axis box, ticks and their numbers.
    for (int i = 0; i < f.x.count(); ++i) {
        const int px = static_cast<int>(std::floor(map.toX(f.x.value(i))));
        fillRect(image, px, f.top, px, f.bottom, kGrid);
    }
    for (int i = 0; i < f.y.count(); ++i) {
        const int py = static_cast<int>(std::floor(map.toY(f.y.value(i), f.y)));
        fillRect(image, f.left, py, f.right, py, kGrid);
    }
    fillRect(image, f.left, f.top, f.right, f.top, kBlack);
    fillRect(image, f.left, f.bottom, f.right, f.bottom, kBlack);
    fillRect(image, f.left, f.top, f.left, f.bottom, kBlack);
    fillRect(image, f.right, f.top, f.right, f.bottom, kBlack);
    for (int i = 0; i < f.x.count(); ++i) {
        const int px = static_cast<int>(std::floor(map.toX(f.x.value(i))));
        fillRect(image, px, f.bottom + 1, px, f.bottom + kTickLength, kBlack);
        const std::string label = formatTick(f.x.value(i), f.x.step);
        drawText(image, px - textWidth(label) / 2, f.bottom + kTickLength + kGap, label, kBlack);
    }
    auto yTicks = [&](const AxisTicks& t, bool right) {
        for (int i = 0; i < t.count(); ++i) {
            const int py = static_cast<int>(std::floor(map.toY(t.value(i), t)));
            const std::string label = formatTick(t.value(i), t.step);
            if (right) {
                fillRect(image, f.right + 1, py, f.right + kTickLength, py, kBlack);
                drawText(image, f.right + kTickLength + kGap, py - kGlyphHeight / 2, label, kBlack);
            } else {
                fillRect(image, f.left - kTickLength, py, f.left - 1, py, kBlack);
                drawText(image, f.left - kTickLength - kGap - textWidth(label),
                         py - kGlyphHeight / 2, label, kBlack);
            }
        }
    };
    yTicks(f.y, false);
    if (f.hasRightAxis) yTicks(f.yRight, true);

    // Step 2: title and axis labels.
    const int centreX = (f.left + f.right) / 2, centreY = (f.top + f.bottom) / 2;
    if (!spec.title.empty()) {
        drawText(image, centreX - textWidth(spec.title, kTitleScale) / 2, kOuterMargin, spec.title,
                 kBlack, kTitleScale);
    }
    if (!spec.xLabel.empty()) {
        drawText(image, centreX - textWidth(spec.xLabel) / 2,
                 spec.height - kOuterMargin - kGlyphHeight, spec.xLabel, kBlack);
    }
    if (!spec.yLabel.empty())
        drawTextVertical(image, kOuterMargin, centreY + textWidth(spec.yLabel) / 2, spec.yLabel,
                         kBlack);
    if (f.hasRightAxis && !spec.yRightLabel.empty()) {
        drawTextVertical(image, spec.width - kOuterMargin - kGlyphHeight,
                         centreY + textWidth(spec.yRightLabel) / 2, spec.yRightLabel, kBlack);
    }

    // Step 3: series lines (broken at non-finite points) and markers.
    for (const PlotSeries& s : spec.series) {
        const AxisTicks& axis = s.rightAxis ? f.yRight : f.y;
        bool havePrevious = false;
        double prevX = 0, prevY = 0;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
                havePrevious = false;
                continue;
            }
            const double px = map.toX(s.x[i]), py = map.toY(s.y[i], axis);
            if (havePrevious) drawLine(image, f, prevX, prevY, px, py, s.color);
            prevX = px;
            prevY = py;
            havePrevious = true;
        }
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
                drawMarker(image, f, map.toX(s.x[i]), map.toY(s.y[i], axis), s.color);
        }
    }

    // Step 4: legend box in the top-right corner of the plot area.
    std::vector<std::pair<std::string, Vec3f>> entries;
    for (const PlotSeries& s : spec.series) {
        if (s.label.empty()) continue;
        entries.emplace_back(s.label + (f.hasRightAxis && s.rightAxis ? " (right)" : ""), s.color);
    }
    if (!entries.empty()) {
        int labelWidth = 0;
        for (const auto& e : entries) labelWidth = std::max(labelWidth, textWidth(e.first));
        const int sample = 20;
        const int boxW = kGap * 2 + sample + kGap + labelWidth + kGap;
        const int boxH = kGap + static_cast<int>(entries.size()) * kLegendRowHeight;
        const int x0 = f.right - kOuterMargin - boxW, y0 = f.top + kOuterMargin;
        fillRect(image, x0, y0, x0 + boxW, y0 + boxH, kLegendBorder);
        fillRect(image, x0 + 1, y0 + 1, x0 + boxW - 1, y0 + boxH - 1, Vec3f(1.f, 1.f, 1.f));
        for (size_t i = 0; i < entries.size(); ++i) {
            const int rowY = y0 + kGap + static_cast<int>(i) * kLegendRowHeight;
            const int midY = rowY + kGlyphHeight / 2;
            const Vec3f c = entries[i].second;
            fillRect(image, x0 + 2 * kGap, midY, x0 + 2 * kGap + sample - 1, midY + 1, c);
            fillRect(image, x0 + 2 * kGap + sample / 2 - 2, midY - 2,
                     x0 + 2 * kGap + sample / 2 + 2, midY + 2, c);
            drawText(image, x0 + 2 * kGap + sample + kGap, rowY, entries[i].first, kBlack);
        }
    }
    return image;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/annotate/legend.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "uvr/core/error.h"
#include "uvr/core/text.h"

namespace uvr {

namespace {

/// 10^e as exactly as doubles allow (a division by an exact power for small numbers).
double pow10(int e) {
    return e >= 0 ? std::pow(10.0, e) : 1.0 / std::pow(10.0, -e);
}

/// m * 10^e, correctly rounded where 10^|e| is exact (|e| <= 22).
double scaled(double m, int e) {
    return e >= 0 ? m * std::pow(10.0, e) : m / std::pow(10.0, -e);
}

/// Linear ticks: multiples of 1, 2 or 5 times a power of ten (Heckbert's nice numbers, tight to
/// the range), the count closest to target within [2, maxCount]; {lo, hi} when none fits.
std::vector<double> linearTicks(double lo, double hi, int target, int maxCount) {
    const double span = hi - lo;
    if (!std::isfinite(span)) return {lo, hi};
    const int e0 = static_cast<int>(std::floor(std::log10(span / std::max(target - 1, 1))));
    double bestM = 0.0, bestScore = 1e300;
    int bestE = 0;
    double bestLo = 0.0, bestHi = -1.0;
    for (int e = e0 - 1; e <= e0 + 1; ++e)
        for (double m : {1.0, 2.0, 5.0}) {
            const double step = m * pow10(e);
            const double kLo = std::ceil(lo / step - 1e-9), kHi = std::floor(hi / step + 1e-9);
            const double count = kHi - kLo + 1.0;
            if (count < 2.0 || count > maxCount) continue;
            const double score = std::fabs(count - target);
            if (score < bestScore)  // steps grow along the loop: a tie keeps the smaller step
                bestScore = score, bestM = m, bestE = e, bestLo = kLo, bestHi = kHi;
        }
    if (bestM == 0.0) return {lo, hi};
    std::vector<double> out;
    for (double k = bestLo; k <= bestHi; k += 1.0)
        out.push_back(std::clamp(scaled(k * bestM, bestE), lo, hi));
    return out;
}

std::vector<double> logTicks(double lo, double hi, int target, int maxCount) {
    const int a = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
    const int b = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
    std::vector<double> decades, oneTwoFive;
    // Decades: 10^k for k the multiples of a 1-2-5 stride of exponents.
    for (int stride : {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000}) {
        const int first = static_cast<int>(std::ceil(double(a) / stride)) * stride;
        if (first <= b && (b - first) / stride + 1 > maxCount) continue;
        for (int k = first; k <= b; k += stride) decades.push_back(std::clamp(pow10(k), lo, hi));
        break;
    }
    if (decades.size() >= 3) return decades;
    // Two decades or less: 1, 2 and 5 times 10^k where they fit.
    for (int k = a - 1; k <= b; ++k)
        for (double m : {1.0, 2.0, 5.0}) {
            const double v = scaled(m, k);
            if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9))
                oneTwoFive.push_back(std::clamp(v, lo, hi));
        }
    if (oneTwoFive.size() >= 2 && static_cast<int>(oneTwoFive.size()) <= maxCount)
        return oneTwoFive;
    if (decades.size() >= 2) return decades;
    return linearTicks(lo, hi, target, maxCount);
}

std::string format(const char* fmt, int digits, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, digits, v);
    return buf;
}

/// The fewest digits (0..maxDigits) for which fmt gives every value within tol; -1 if none.
int fewestDigits(const std::vector<double>& values, const char* fmt, double tol, int maxDigits) {
    for (int d = 0; d <= maxDigits; ++d) {
        bool ok = true;
        for (double v : values)
            ok = ok && std::fabs(std::strtod(format(fmt, d, v).c_str(), nullptr) - v) <= tol;
        if (ok) return d;
    }
    return -1;
}

const char* const kSuperscript[] = {"\u2070", "\u00B9", "\u00B2", "\u00B3", "\u2074",
                                    "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};

/// A number from printf's %f or %e, in the legend's style: "1.5e-30" (no '+', no leading zeros
/// in the exponent) or with superscripts "10⁶" / "2×10⁻³"; zero unsigned ("0.0" in fixed point,
/// "0" in scientific); U+2212 for minus.
std::string tidy(const std::string& printed, bool superscript) {
    std::string mant = printed, exp;
    const size_t e = printed.find('e');
    if (e != std::string::npos) {
        mant = printed.substr(0, e);
        exp = std::to_string(std::atoi(printed.c_str() + e + 1));
    }
    if (mant.find_first_of("123456789") == std::string::npos)  // zero, also "-0.0"
        return exp.empty() ? mant.substr(mant[0] == '-' ? 1 : 0) : "0";
    std::string out;
    if (mant[0] == '-') out = "\u2212", mant.erase(0, 1);
    if (!superscript && (exp.empty() || exp == "0")) {
        out += mant;
    } else if (!superscript) {
        out += mant + "e" + (exp[0] == '-' ? "\u2212" + exp.substr(1) : exp);
    } else {
        if (mant != "1") out += mant + "\u00D7";
        out += "10";
        for (char c : exp) out += c == '-' ? "\u207B" : kSuperscript[c - '0'];
    }
    return out;
}

void fillRect(Image& image, PixelRect r, Vec3f color, float alpha) {
    r.x0 = std::max(r.x0, 0), r.y0 = std::max(r.y0, 0);
    r.x1 = std::min(r.x1, image.width), r.y1 = std::min(r.y1, image.height);
    for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) blendOver(image, x, y, color, alpha);
}

/// The title cut to at most maxWidth pixels with a trailing ellipsis. A name from a file may be
/// megabytes long: a title is cut after kMaxTitleChars characters whatever the width, and the cut
/// is found by bisection (advances only grow along a text), so it costs a few short layouts.
std::string fitTitle(const Font& font, const std::string& title, float size, int maxWidth) {
    constexpr size_t kMaxTitleChars = 512;
    std::u32string cps = decodeUtf8Lossy(title.substr(0, 4 * kMaxTitleChars));
    const bool cut = cps.size() > kMaxTitleChars || title.size() > 4 * kMaxTitleChars;
    if (cps.size() > kMaxTitleChars) cps.resize(kMaxTitleChars);
    if (!cut && font.advance(title, size) <= maxWidth) return title;
    const auto shortened = [&](size_t n) { return encodeUtf8(cps.substr(0, n)) + "\u2026"; };
    size_t lo = 0, hi = cps.size();  // shortened(lo) fits (or lo is 0); find the longest
    while (lo < hi) {
        const size_t mid = (lo + hi + 1) / 2;
        if (font.advance(shortened(mid), size) <= maxWidth)
            lo = mid;
        else
            hi = mid - 1;
    }
    return shortened(lo);
}

}  // namespace

LegendTicks legendTicks(double lo, double hi, bool logScale, int target, int maxCount) {
    if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi)
        throwError(ErrorKind::Argument, "",
                   "legend range " + std::to_string(lo) + ".." + std::to_string(hi) +
                       ": expected finite lo <= hi");
    if (maxCount < 2)
        throwError(ErrorKind::Argument, "", "legend ticks: at least 2 must be allowed");
    if (logScale && !(lo > 0.0))
        throwError(ErrorKind::Argument, "",
                   "legend range " + std::to_string(lo) + ".." + std::to_string(hi) +
                       ": a log scale needs lo > 0");
    target = std::clamp(target, 2, maxCount);
    LegendTicks t;
    if (lo == hi)
        t.values = {lo};
    else
        t.values =
            logScale ? logTicks(lo, hi, target, maxCount) : linearTicks(lo, hi, target, maxCount);
    t.labels = formatTickLabels(t.values, logScale);
    return t;
}

std::vector<std::string> formatTickLabels(const std::vector<double>& values, bool logScale) {
    std::vector<std::string> out;
    if (values.empty()) return out;
    double maxAbs = 0.0, gap = 0.0;
    for (size_t i = 0; i < values.size(); ++i) {
        maxAbs = std::max(maxAbs, std::fabs(values[i]));
        if (i > 0 && values[i] != values[i - 1]) {
            const double g = std::fabs(values[i] - values[i - 1]);
            gap = gap == 0.0 ? g : std::min(gap, g);
        }
    }
    const bool fixed = maxAbs == 0.0 || (maxAbs >= 1e-3 && maxAbs < 1e5);
    if (logScale) {  // each label its own shortest form, good to 1e-9 of itself
        double minAbs = maxAbs;
        for (double v : values) minAbs = std::min(minAbs, std::fabs(v));
        const bool fixedAll = maxAbs < 1e5 && minAbs >= 1e-3;
        for (double v : values) {
            const std::vector<double> one{v};
            const double tol = std::fabs(v) * 1e-9;
            const int fd = fixedAll ? fewestDigits(one, "%.*f", tol, 6) : -1;
            out.push_back(
                fd >= 0 ? tidy(format("%.*f", fd, v), false)
                        : tidy(format("%.*e", std::max(0, fewestDigits(one, "%.*e", tol, 15)), v),
                               true));
        }
        return out;
    }
    // One format for all: good to 1e-6 of the smallest gap (of the value itself for one value).
    const double tol = gap > 0.0 ? gap * 1e-6 : maxAbs * 1e-9;
    int digits = fixed ? fewestDigits(values, "%.*f", tol, 6) : -1;
    const char* fmt = "%.*f";
    if (digits < 0) {
        fmt = "%.*e";
        digits = std::max(0, fewestDigits(values, fmt, tol, 15));
    }
    for (double v : values) out.push_back(tidy(format(fmt, digits, v), false));
    return out;
}

double legendPosition(double v, double lo, double hi, bool logScale) {
    if (!(hi > lo)) return 0.5;
    const double t = logScale && lo > 0.0 && v > 0.0 ? std::log(v / lo) / std::log(hi / lo)
                                                     : (v - lo) / (hi - lo);
    return std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
}

void addRangeEnds(LegendTicks& ticks, double lo, double hi, bool logScale, double gap) {
    if (!(hi > lo)) return;
    const auto at = [&](double v) { return legendPosition(v, lo, hi, logScale); };
    const auto same = [&](double a, double b) {
        return std::fabs(a - b) <= 1e-9 * std::max(std::fabs(a), std::fabs(b));
    };
    const auto label = [](double v) {
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.4g", v);
        return tidy(buf, false);
    };
    LegendTicks out;
    const bool loTick = !ticks.values.empty() && same(ticks.values.front(), lo);
    const bool hiTick = !ticks.values.empty() && same(ticks.values.back(), hi);
    if (!loTick) out.values.push_back(lo), out.labels.push_back(label(lo));
    for (std::size_t i = 0; i < ticks.values.size(); ++i) {
        const double t = at(ticks.values[i]);
        const bool end = (i == 0 && loTick) || (i + 1 == ticks.values.size() && hiTick);
        if (!end && ((!loTick && t < gap) || (!hiTick && t > 1.0 - gap))) continue;
        out.values.push_back(ticks.values[i]);
        out.labels.push_back(ticks.labels[i]);
    }
    if (!hiTick) out.values.push_back(hi), out.labels.push_back(label(hi));
    ticks = std::move(out);
}

namespace {

/// Error(Argument) unless the image is at least kLegendMinWidth x kLegendMinHeight.
void requireAnnotatable(const Image& image, const char* what) {
    if (image.width < kLegendMinWidth || image.height < kLegendMinHeight)
        throwError(ErrorKind::Argument, "",
                   std::string(what) + " needs an image of at least " +
                       std::to_string(kLegendMinWidth) + "x" + std::to_string(kLegendMinHeight) +
                       " pixels, not " + std::to_string(image.width) + "x" +
                       std::to_string(image.height));
}

/// An annotation's backing box colour (the background, white on a transparent image) and the
/// one of near-black and near-white ink that contrasts with it.
std::pair<Vec3f, Vec3f> boxAndInk(const LegendStyle& style) {
    const Vec3f box = style.background.value_or(Vec3f{1.f, 1.f, 1.f});
    const float luminance = 0.2126f * box.x + 0.7152f * box.y + 0.0722f * box.z;
    return {box, luminance > 0.45f ? Vec3f{0.08f, 0.08f, 0.08f} : Vec3f{0.95f, 0.95f, 0.95f}};
}

}  // namespace

PixelRect drawCornerText(Image& image, const Font& font, const std::string& text,
                         const LegendStyle& style) {
    requireAnnotatable(image, "a label");
    const int W = image.width, H = image.height;
    const float u = std::max(10.f, std::round(std::min(H / 40.f, W / 24.f)));
    const int margin = std::max(1, static_cast<int>(std::lround(0.8f * u)));
    const int pad = std::max(1, static_cast<int>(std::lround(0.6f * u)));
    const std::string shown = fitTitle(font, text, u, static_cast<int>(0.9f * W) - 2 * pad);
    const FontMetrics m = font.metrics(u);
    const int ascent = static_cast<int>(std::ceil(m.ascender));
    const int height = static_cast<int>(std::ceil(m.ascender + m.descender));
    PixelRect box{margin, margin, margin + font.advance(shown, u) + 2 * pad,
                  margin + height + 2 * pad};
    const auto [boxColor, ink] = boxAndInk(style);
    fillRect(image, box, boxColor, 0.8f);
    font.draw(image, shown, u, box.x0 + pad, box.y0 + pad + ascent, ink);
    return box;
}

namespace {

/// A legend's layout and what drawing it needs beyond LegendLayout.
struct LegendPlan {
    LegendLayout L;
    std::string shownTitle;
    float u = 0.f, titleSize = 0.f;
    int line = 1, tickLength = 1, labelGap = 1, titleAscent = 0, barHeight = 1, margin = 1;
    TextBox digit;
};

LegendPlan planLegend(int W, int H, const Font& font, double lo, double hi,
                      const std::string& title, bool logScale, const LegendStyle& style) {
    legendTicks(lo, hi, logScale);  // a bad range fails before anything is drawn
    // Sizes: everything in units of the label size u, about 1/40 of the height.
    LegendPlan P;
    LegendLayout& L = P.L;
    const float u = std::max(10.f, std::round(std::min(H / 40.f, W / 24.f)));
    P.u = u;
    P.titleSize = std::round(u * 1.15f);
    L.fontSize = u;
    const auto px = [&](float f) { return std::max(1, static_cast<int>(std::lround(f * u))); };
    const int margin = px(0.8f), pad = px(0.6f), barWidth = px(1.1f), titleGap = px(0.7f);
    P.margin = margin;
    P.tickLength = px(0.35f);
    P.labelGap = px(0.3f);
    P.line = std::max(1, px(1.f / 14.f));
    const int line = P.line;
    P.digit = font.inkBox("0", u);
    const int digitHeight = std::max(1, P.digit.y1 - P.digit.y0);
    const FontMetrics tm = font.metrics(P.titleSize);
    P.titleAscent = static_cast<int>(std::ceil(tm.ascender));
    const int titleHeight = static_cast<int>(std::ceil(tm.ascender + tm.descender));

    // The bar: half the height, less where the title and the box would not fit.
    const int frame = titleHeight + titleGap + digitHeight + 2 * (pad + margin);
    const int barHeight = std::max(digitHeight * 2, std::min(H / 2, H - frame));
    P.barHeight = barHeight;
    // Labels at least 1.8 digit heights apart.
    const int maxTicks = std::clamp(barHeight / (digitHeight * 9 / 5) + 1, 2, 8);
    L.ticks = legendTicks(lo, hi, logScale, std::min(5, maxTicks), maxTicks);
    addRangeEnds(L.ticks, lo, hi, logScale, (digitHeight * 9.0 / 5.0) / barHeight);
    int labelWidth = 0;
    for (const std::string& s : L.ticks.labels)
        labelWidth = std::max(labelWidth, font.advance(s, u));
    const int scaleWidth = line + barWidth + line + P.tickLength + P.labelGap + labelWidth;
    P.shownTitle = fitTitle(font, title, P.titleSize,
                            std::max(scaleWidth, static_cast<int>(0.45f * W) - 2 * (pad + margin)));
    const int titleWidth = font.advance(P.shownTitle, P.titleSize);
    const int contentWidth = std::max(scaleWidth, titleWidth);
    const int contentHeight =
        titleHeight + titleGap + digitHeight / 2 + barHeight + digitHeight / 2 + line;

    // Placement: at the chosen edge, vertically centred.
    L.box.x0 =
        style.position == LegendPosition::Right ? W - margin - contentWidth - 2 * pad : margin;
    L.box.x1 = L.box.x0 + contentWidth + 2 * pad;
    L.box.y0 = (H - contentHeight - 2 * pad) / 2;
    L.box.y1 = L.box.y0 + contentHeight + 2 * pad;
    const int left = L.box.x0 + pad, top = L.box.y0 + pad;
    L.title = {left, top, left + titleWidth, top + titleHeight};
    L.bar.x0 = left + line;
    L.bar.x1 = L.bar.x0 + barWidth;
    L.bar.y0 = top + titleHeight + titleGap + digitHeight / 2;
    L.bar.y1 = L.bar.y0 + barHeight;
    // The columns from the image's edge to the box and its margin again beyond it, at most a
    // third of the width (a long title's box is wider).
    L.columns = std::min(
        W / 3, style.position == LegendPosition::Right ? W - L.box.x0 + margin : L.box.x1 + margin);
    return P;
}

}  // namespace

LegendLayout legendLayout(int width, int height, const Font& font, double lo, double hi,
                          const std::string& title, bool logScale, const LegendStyle& style) {
    return planLegend(width, height, font, lo, hi, title, logScale, style).L;
}

LegendLayout drawLegend(Image& image, const Font& font, const TransferFunction& tf, double lo,
                        double hi, const std::string& title, bool logScale,
                        const LegendStyle& style) {
    requireAnnotatable(image, "a legend");
    const LegendPlan P =
        planLegend(image.width, image.height, font, lo, hi, title, logScale, style);
    LegendLayout L = P.L;
    const int line = P.line, barHeight = P.barHeight;
    const int top = L.title.y0;

    // Colours: the box as the background (white on a transparent image), text contrasting.
    const auto [boxColor, ink] = boxAndInk(style);

    // Drawing: box, title, bar with its frame, tick marks and labels.
    fillRect(image, L.box, boxColor, 0.8f);
    font.draw(image, P.shownTitle, P.titleSize, L.title.x0, top + P.titleAscent, ink);
    for (int y = L.bar.y0; y < L.bar.y1; ++y) {
        const float t = (L.bar.y1 - y - 0.5f) / barHeight;
        fillRect(image, {L.bar.x0, y, L.bar.x1, y + 1}, tf.colorAt(t), 1.f);
    }
    fillRect(image, {L.bar.x0 - line, L.bar.y0 - line, L.bar.x1 + line, L.bar.y0}, ink, 1.f);
    fillRect(image, {L.bar.x0 - line, L.bar.y1, L.bar.x1 + line, L.bar.y1 + line}, ink, 1.f);
    fillRect(image, {L.bar.x0 - line, L.bar.y0, L.bar.x0, L.bar.y1}, ink, 1.f);
    fillRect(image, {L.bar.x1, L.bar.y0, L.bar.x1 + line, L.bar.y1}, ink, 1.f);
    const int labelX = L.bar.x1 + line + P.tickLength + P.labelGap;
    for (size_t i = 0; i < L.ticks.values.size(); ++i) {
        const double t = legendPosition(L.ticks.values[i], lo, hi, logScale);
        const int row = std::clamp(static_cast<int>(std::floor(L.bar.y1 - t * barHeight)), L.bar.y0,
                                   L.bar.y1 - 1);
        L.tickRows.push_back(row);
        const int y0 = row - (line - 1) / 2;
        fillRect(image, {L.bar.x1, y0, L.bar.x1 + line + P.tickLength, y0 + line}, ink, 1.f);
        // Digits centred on the tick: their ink box runs from digit.y0 to digit.y1 about the
        // baseline.
        const int baseline = row - (P.digit.y0 + P.digit.y1) / 2;
        font.draw(image, L.ticks.labels[i], P.u, labelX, baseline, ink);
    }
    return L;
}

Camera cameraBesideLegend(const PreparedMesh& mesh, const RenderSettings& settings,
                          const Bounds3f& fileBounds, const Font& font, const std::string& title) {
    const auto [lo, hi] = frameValueRange(mesh, settings);
    const int w = settings.width, h = settings.height;
    const LegendLayout layout = legendLayout(w, h, font, lo, hi, title, settings.tf.logScale);
    return clearColumns(settings.camera.value_or(resetCamera(fileBounds, float(w) / float(h))), w,
                        h, layout.columns);
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/render/image_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "uvr/core/error.h"

namespace uvr {

namespace {

/// SSIM constants of Wang et al. 2004 for 8-bit data.
constexpr double kSsimSigma = 1.5;
constexpr double kSsimK1 = 0.01;
constexpr double kSsimK2 = 0.03;
constexpr double kDataRange = 255.0;
/// Gaussian radius: int(truncate * sigma + 0.5) with truncate 3.5, i.e. an 11-tap window.
constexpr int kSsimRadius = 5;
constexpr int kSsimWindow = 2 * kSsimRadius + 1;

std::string sizeText(int w, int h) {
    return std::to_string(w) + "x" + std::to_string(h);
}

void checkRgb8(const Rgb8Image& image, const char* which) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgb.size() != static_cast<size_t>(image.width) * image.height * 3) {
        throwError(ErrorKind::Argument, "",
                   std::string("image ") + which + " is " + sizeText(image.width, image.height) +
                       " with " + std::to_string(image.rgb.size()) +
                       " RGB values; expected width * height * 3 values");
    }
}

/// Normalised Gaussian weights exp(-x^2 / (2 sigma^2)), x = -radius..radius (scipy.ndimage).
std::array<double, kSsimWindow> gaussianWeights() {
    std::array<double, kSsimWindow> w{};
    double sum = 0.0;
    for (int i = -kSsimRadius; i <= kSsimRadius; ++i) {
        w[i + kSsimRadius] = std::exp(-0.5 / (kSsimSigma * kSsimSigma) * i * i);
        sum += w[i + kSsimRadius];
    }
    for (double& v : w) v /= sum;
    return w;
}

/// Mean SSIM of one channel (Wang et al. 2004) over the pixels at least kSsimRadius from every
/// border. scikit-image filters with reflected borders and then crops that same radius, so the
/// kept pixels' windows lie entirely inside the image and no border handling is needed here.
double channelSsim(const Rgb8Image& a, const Rgb8Image& b, int channel) {
    const auto w = gaussianWeights();
    const int width = a.width;
    const int innerW = width - 2 * kSsimRadius;
    const int innerH = a.height - 2 * kSsimRadius;

    // The separable Gaussian's horizontal pass of x, y, x^2, y^2 and xy for the kept columns,
    // kept for the last kSsimWindow image rows in a ring buffer.
    constexpr int kMoments = 5;
    std::vector<double> ring(static_cast<size_t>(kMoments) * kSsimWindow * innerW);
    std::vector<double> rowA(width), rowB(width);
    auto ringRow = [&](int moment, int imageRow) {
        return &ring[(static_cast<size_t>(moment) * kSsimWindow + imageRow % kSsimWindow) * innerW];
    };
    auto filterRow = [&](int y) {
        for (int x = 0; x < width; ++x) {
            const size_t i = (static_cast<size_t>(y) * width + x) * 3 + channel;
            rowA[x] = a.rgb[i];
            rowB[x] = b.rgb[i];
        }
        double* out[kMoments];
        for (int m = 0; m < kMoments; ++m) out[m] = ringRow(m, y);
        for (int x = 0; x < innerW; ++x) {
            double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
            for (int k = 0; k < kSsimWindow; ++k) {
                const double va = rowA[x + k], vb = rowB[x + k], wk = w[k];
                sx += wk * va;
                sy += wk * vb;
                sxx += wk * va * va;
                syy += wk * vb * vb;
                sxy += wk * va * vb;
            }
            out[0][x] = sx;
            out[1][x] = sy;
            out[2][x] = sxx;
            out[3][x] = syy;
            out[4][x] = sxy;
        }
    };

    // Vertical pass for each kept row, then the SSIM map and its mean.
    const double c1 = (kSsimK1 * kDataRange) * (kSsimK1 * kDataRange);
    const double c2 = (kSsimK2 * kDataRange) * (kSsimK2 * kDataRange);
    std::vector<double> sums(static_cast<size_t>(kMoments) * innerW);
    for (int y = 0; y < kSsimWindow - 1; ++y) filterRow(y);
    double total = 0.0;
    for (int y = 0; y < innerH; ++y) {
        filterRow(y + kSsimWindow - 1);
        std::fill(sums.begin(), sums.end(), 0.0);
        for (int m = 0; m < kMoments; ++m) {
            double* sum = &sums[static_cast<size_t>(m) * innerW];
            for (int k = 0; k < kSsimWindow; ++k) {
                const double* row = ringRow(m, y + k);
                for (int x = 0; x < innerW; ++x) sum[x] += w[k] * row[x];
            }
        }
        const double* ux = &sums[0];
        const double* uy = &sums[static_cast<size_t>(innerW)];
        const double* uxx = &sums[2 * static_cast<size_t>(innerW)];
        const double* uyy = &sums[3 * static_cast<size_t>(innerW)];
        const double* uxy = &sums[4 * static_cast<size_t>(innerW)];
        double rowSum = 0.0;
        for (int x = 0; x < innerW; ++x) {
            const double vx = uxx[x] - ux[x] * ux[x];
            const double vy = uyy[x] - uy[x] * uy[x];
            const double vxy = uxy[x] - ux[x] * uy[x];
            const double num = (2 * ux[x] * uy[x] + c1) * (2 * vxy + c2);
            const double den = (ux[x] * ux[x] + uy[x] * uy[x] + c1) * (vx + vy + c2);
            rowSum += num / den;
        }
        total += rowSum;
    }
    return total / (static_cast<double>(innerW) * innerH);
}

/// What differenceMeasures marks a pixel as.
constexpr std::uint8_t kMarkSeam = 1;
constexpr std::uint8_t kMarkSpeckle = 2;

/// The per-pixel measures of ImageComparison (percentile, maximum, fraction off, seams,
/// speckle) of images of the same, checked size, with A the reference; marks (one per pixel:
/// 0, kMarkSeam or kMarkSpeckle) is filled for differenceImage.
void differenceMeasures(const Rgb8Image& a, const Rgb8Image& b, ImageComparison& r,
                        std::vector<std::uint8_t>& marks) {
    const int w = a.width, h = a.height;
    const size_t n = static_cast<size_t>(w) * h;
    auto at = [w](int x, int y) { return static_cast<size_t>(y) * w + x; };
    // The signed difference S_c = A_c - B_c of every value.
    std::vector<int> s(n * 3);
    for (size_t i = 0; i < n * 3; ++i) s[i] = static_cast<int>(a.rgb[i]) - b.rgb[i];

    // The distribution of D = max_c |S_c|: maximum, pixels off, 99.9th percentile (numpy's
    // linear interpolation between the ranks floor(0.999 (n - 1)) and the next).
    std::array<size_t, 256> histogram{};
    for (size_t i = 0; i < n; ++i) {
        const int d =
            std::max({std::abs(s[i * 3]), std::abs(s[i * 3 + 1]), std::abs(s[i * 3 + 2])});
        ++histogram[d];
    }
    auto valueAtRank = [&](size_t rank) {
        size_t below = 0;
        for (int v = 0; v < 256; ++v) {
            below += histogram[v];
            if (rank < below) return v;
        }
        return 255;
    };
    const double position = 0.999 * static_cast<double>(n - 1);
    const size_t lowRank = static_cast<size_t>(position);
    const int low = valueAtRank(lowRank), high = valueAtRank(std::min(lowRank + 1, n - 1));
    r.p999Difference = low + (position - static_cast<double>(lowRank)) * (high - low);
    size_t off = 0;
    for (int v = 0; v < 256; ++v) {
        if (histogram[v] != 0) r.maxAbsDifference = v;
        if (v > kDifferenceLevelsOff) off += histogram[v];
    }
    r.fractionOff = static_cast<double>(off) / static_cast<double>(n);

    // Seam edges: sharp steps of S where A is smooth, by direction (right, down) and sign.
    marks.assign(n, 0);
    r.seamCount = 0;
    r.longestSeam = 0;
    std::vector<signed char> sign(n);
    std::vector<char> visited(n);
    std::vector<int> stack, group;
    for (int dir = 0; dir < 2; ++dir) {
        const int dx = dir == 0 ? 1 : 0, dy = 1 - dx;
        std::fill(sign.begin(), sign.end(), 0);
        for (int y = dy; y + 2 * dy < h; ++y) {
            for (int x = dx; x + 2 * dx < w; ++x) {
                const size_t p = at(x, y), q = at(x + dx, y + dy);
                const size_t before = at(x - dx, y - dy), after = at(x + 2 * dx, y + 2 * dy);
                int best = 0;
                for (int c = 0; c < 3; ++c) {
                    const int j = s[q * 3 + c] - s[p * 3 + c];
                    const int aj = std::abs(j);
                    const int stepBefore = std::abs(s[p * 3 + c] - s[before * 3 + c]);
                    const int stepAfter = std::abs(s[after * 3 + c] - s[q * 3 + c]);
                    const int reference = std::abs(a.rgb[q * 3 + c] - a.rgb[p * 3 + c]);
                    if (aj >= kSeamMinStep && aj >= 2 * stepBefore && aj >= 2 * stepAfter &&
                        2 * reference <= aj && aj > best) {
                        best = aj;
                        sign[p] = j > 0 ? 1 : -1;
                    }
                }
            }
        }
        // 8-connected groups of seam edges of one sign; thin, long groups are seams.
        std::fill(visited.begin(), visited.end(), 0);
        for (size_t start = 0; start < n; ++start) {
            if (sign[start] == 0 || visited[start]) continue;
            visited[start] = 1;
            stack.assign(1, static_cast<int>(start));
            group.clear();
            int lo = std::numeric_limits<int>::max(), hi = -1;
            while (!stack.empty()) {
                const int i = stack.back();
                stack.pop_back();
                group.push_back(i);
                const int x = i % w, y = i / w;
                const int along = dir == 0 ? y : x;
                lo = std::min(lo, along);
                hi = std::max(hi, along);
                for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, h - 1); ++ny) {
                    for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, w - 1); ++nx) {
                        const size_t k = at(nx, ny);
                        if (sign[k] == sign[start] && !visited[k]) {
                            visited[k] = 1;
                            stack.push_back(static_cast<int>(k));
                        }
                    }
                }
            }
            const int length = hi - lo + 1;
            if (length >= kSeamMinLength && group.size() <= 2 * static_cast<size_t>(length)) {
                ++r.seamCount;
                r.longestSeam = std::max(r.longestSeam, length);
                for (int i : group) marks[i] = kMarkSeam;
            }
        }
    }

    // Speckle: pixels far from the median of their 3x3 neighbourhood in S where A is smooth.
    size_t speckle = 0;
    for (int y = 1; y + 1 < h; ++y) {
        for (int x = 1; x + 1 < w; ++x) {
            bool isSpeckle = false;
            for (int c = 0; c < 3 && !isSpeckle; ++c) {
                std::array<int, 9> window;
                int lo = 255, hi = 0, k = 0;
                for (int ny = y - 1; ny <= y + 1; ++ny) {
                    for (int nx = x - 1; nx <= x + 1; ++nx) {
                        const size_t i = at(nx, ny) * 3 + c;
                        window[k++] = s[i];
                        lo = std::min<int>(lo, a.rgb[i]);
                        hi = std::max<int>(hi, a.rgb[i]);
                    }
                }
                std::nth_element(window.begin(), window.begin() + 4, window.end());
                const int deviation = std::abs(s[at(x, y) * 3 + c] - window[4]);
                isSpeckle = deviation >= kSpeckleMinDeviation && deviation > hi - lo;
            }
            if (isSpeckle) {
                ++speckle;
                if (marks[at(x, y)] == 0) marks[at(x, y)] = kMarkSpeckle;
            }
        }
    }
    r.speckleFraction = static_cast<double>(speckle) / static_cast<double>(n);
    r.seamPixels = static_cast<int>(std::count(marks.begin(), marks.end(), kMarkSeam));
}

/// Checks two images for compareImages and differenceImage.
void checkPair(const Rgb8Image& a, const Rgb8Image& b) {
    checkRgb8(a, "A");
    checkRgb8(b, "B");
    if (a.width != b.width || a.height != b.height) {
        throwError(ErrorKind::Argument, "",
                   "cannot compare a " + sizeText(a.width, a.height) + " image with a " +
                       sizeText(b.width, b.height) + " image; expected the same size");
    }
    if (a.width < kSsimWindow || a.height < kSsimWindow) {
        throwError(ErrorKind::Argument, "",
                   "cannot compute SSIM of " + sizeText(a.width, a.height) +
                       " images; expected at least 11x11 pixels (the Gaussian window)");
    }
}

}  // namespace

Rgb8Image toRgb8(const Image& image, Vec3f background) {
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != static_cast<size_t>(image.width) * image.height) {
        throwError(ErrorKind::Argument, "",
                   "cannot convert a " + sizeText(image.width, image.height) + " image with " +
                       std::to_string(image.pixels.size()) + " pixels to 8-bit RGB");
    }
    Rgb8Image out;
    out.width = image.width;
    out.height = image.height;
    out.rgb.resize(image.pixels.size() * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i)
        compositeToRgb8(image.pixels[i], background, &out.rgb[i * 3]);
    return out;
}

ImageComparison compareImages(const Rgb8Image& a, const Rgb8Image& b) {
    checkPair(a, b);
    ImageComparison result;
    for (int c = 0; c < 3; ++c) result.ssimChannel[c] = channelSsim(a, b, c);
    result.ssim = (result.ssimChannel[0] + result.ssimChannel[1] + result.ssimChannel[2]) / 3.0;

    // PSNR over all RGB values (data range 255).
    double squared = 0.0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const int d = static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i]);
        squared += static_cast<double>(d) * d;
    }
    const double mse = squared / static_cast<double>(a.rgb.size());
    result.psnr = mse == 0.0 ? std::numeric_limits<double>::infinity()
                             : 10.0 * std::log10(kDataRange * kDataRange / mse);
    std::vector<std::uint8_t> marks;
    differenceMeasures(a, b, result, marks);
    return result;
}

std::vector<ComparisonField> differenceFields(const ImageComparison& r) {
    return {{"p999_difference", r.p999Difference, false},
            {"max_abs_difference", r.maxAbsDifference, true},
            {"fraction_off", r.fractionOff, false},
            {"seam_count", static_cast<double>(r.seamCount), true},
            {"seam_pixels", static_cast<double>(r.seamPixels), true},
            {"longest_seam", static_cast<double>(r.longestSeam), true},
            {"speckle_fraction", r.speckleFraction, false}};
}

std::string differenceSummary(const ImageComparison& r) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "p99.9 %g/255, max %g/255, %.3g%% of pixels off by more than %d/255, %d seam%s "
                  "(%d pixels, longest %d), speckle %.3g%%",
                  r.p999Difference, r.maxAbsDifference, 100.0 * r.fractionOff, kDifferenceLevelsOff,
                  r.seamCount, r.seamCount == 1 ? "" : "s", r.seamPixels, r.longestSeam,
                  100.0 * r.speckleFraction);
    return text;
}

Rgb8Image differenceImage(const Rgb8Image& a, const Rgb8Image& b) {
    checkPair(a, b);
    ImageComparison measures;
    std::vector<std::uint8_t> marks;
    differenceMeasures(a, b, measures, marks);
    Rgb8Image out;
    out.width = a.width;
    out.height = a.height;
    out.rgb.resize(a.rgb.size());
    for (size_t i = 0; i < marks.size(); ++i) {
        std::uint8_t* px = &out.rgb[i * 3];
        if (marks[i] == kMarkSeam) {
            px[0] = 255, px[1] = 0, px[2] = 0;
        } else if (marks[i] == kMarkSpeckle) {
            px[0] = 255, px[1] = 255, px[2] = 0;
        } else {
            int d = 0;
            for (int c = 0; c < 3; ++c)
                d = std::max(d, std::abs(a.rgb[i * 3 + c] - b.rgb[i * 3 + c]));
            px[0] = px[1] = px[2] = static_cast<std::uint8_t>(std::min(255, 8 * d));
        }
    }
    return out;
}

}  // namespace uvr

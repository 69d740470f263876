// SPDX-License-Identifier: MIT
#include "uvr/render/image_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
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
    ImageComparison result;
    for (int c = 0; c < 3; ++c) result.ssimChannel[c] = channelSsim(a, b, c);
    result.ssim = (result.ssimChannel[0] + result.ssimChannel[1] + result.ssimChannel[2]) / 3.0;

    // PSNR over all RGB values (data range 255) and the largest difference.
    double squared = 0.0;
    int maxDiff = 0;
    for (size_t i = 0; i < a.rgb.size(); ++i) {
        const int d = static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i]);
        squared += static_cast<double>(d) * d;
        maxDiff = std::max(maxDiff, std::abs(d));
    }
    const double mse = squared / static_cast<double>(a.rgb.size());
    result.psnr = mse == 0.0 ? std::numeric_limits<double>::infinity()
                             : 10.0 * std::log10(kDataRange * kDataRange / mse);
    result.maxAbsDifference = maxDiff;
    return result;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr {

/// An 8-bit RGB image (row 0 at the top), as PNG files and image metrics see pixels.
struct Rgb8Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb;  ///< width * height * 3
};

/// Composites a premultiplied image over a background and quantises to 8 bits exactly as
/// writePng does, so metrics on renders and on their PNG files agree; throws Error(Argument) when
/// the image does not hold width * height pixels.
Rgb8Image toRgb8(const Image& image, Vec3f background = Vec3f(0.f, 0.f, 0.f));

/// Thresholds of the per-pixel measures in compareImages, in 8-bit levels (0..255) of
/// premultiplied colour composited over one background.
constexpr int kDifferenceLevelsOff = 4;  ///< a pixel is "off" when its difference exceeds this
constexpr int kSeamMinStep = 2;          ///< smallest jump of the difference across a seam
constexpr int kSeamMinLength = 16;       ///< shortest seam, in pixels along the line
constexpr int kSpeckleMinDeviation = 5;  ///< smallest speckle: |difference - 3x3 median|

/// Similarity of two images of the same size: A is the reference (e.g. the exact integrator's
/// image), B the image judged against it. Every per-pixel measure works on the signed difference
/// S_c = A_c - B_c of the 8-bit values of channel c (R, G, B) and on D = max_c |S_c|.
struct ImageComparison {
    double ssim = 0.0;            ///< mean SSIM over R, G, B
    double ssimChannel[3] = {};   ///< SSIM per channel
    double psnr = 0.0;            ///< PSNR in dB over all RGB values (infinity when identical)
    double maxAbsDifference = 0;  ///< largest per-pixel difference D (0..255)
    /// 99.9th percentile of D over all pixels (background included), interpolated linearly
    /// between the two nearest ranks as numpy.percentile does (0..255).
    double p999Difference = 0;
    /// Fraction of all pixels with D > kDifferenceLevelsOff.
    double fractionOff = 0;
    /// Seams: steps in the difference image where the reference is smooth, connected into lines
    /// at least kSeamMinLength pixels long (see compareImages for the exact rule).
    int seamCount = 0;
    int seamPixels = 0;   ///< pixels on the seams found
    int longestSeam = 0;  ///< length in pixels of the longest seam (0 when none)
    /// Fraction of all pixels that are speckle: isolated pixels of the difference image (see
    /// compareImages for the exact rule).
    double speckleFraction = 0;
};

/// SSIM (Wang et al. 2004: Gaussian window 11x11, sigma 1.5, K1 0.01, K2 0.03, data range 255,
/// population covariances, reflected borders, the 5-pixel border excluded from the mean, as
/// scikit-image's structural_similarity with gaussian_weights=True computes it), PSNR and the
/// per-pixel measures of ImageComparison, with A the reference. The seam rule: the edge between
/// a pixel p and its neighbour q = p + e (e one pixel right or down; p - e and q + e inside the
/// image) is a seam edge when some channel c has a jump j = S_c(q) - S_c(p) with |j| >=
/// kSeamMinStep, |j| >= 2 |S_c(p) - S_c(p - e)| and |j| >= 2 |S_c(q + e) - S_c(q)| (a sharp
/// step, not a ramp or a single odd pixel), and |A_c(q) - A_c(p)| <= |j| / 2 (the reference is
/// smooth there: the edge is not in the picture); its sign is that of the qualifying channel
/// with the largest |j|. Seam edges of the same direction e and sign are joined into 8-connected
/// groups of their pixels p; a group is a seam when its extent along the line (rows spanned for
/// e right, columns for e down) is at least kSeamMinLength and it has at most two pixels per
/// unit of that extent (a thin line, not a blob). The speckle rule: a pixel (one pixel in from
/// the border) is speckle when some channel c has |S_c - median of S_c over its 3x3
/// neighbourhood| >= kSpeckleMinDeviation and larger than the range (max - min) of A_c over that
/// neighbourhood (the reference is smooth there). Throws Error(Argument) when the sizes differ
/// or an image is smaller than 11x11.
ImageComparison compareImages(const Rgb8Image& a, const Rgb8Image& b);

/// One per-pixel measure of an ImageComparison as reports name it (a JSON key, a CSV column).
struct ComparisonField {
    const char* name;  ///< snake_case report name, e.g. "p999_difference"
    double value;      ///< the measure
    bool integer;      ///< a count (of seams or pixels), written as an integer
};

/// The per-pixel measures of r in report order: p999_difference, max_abs_difference (levels
/// 0..255), fraction_off, seam_count, seam_pixels, longest_seam, speckle_fraction. The one
/// spelling every front end (compare, bench, the quality matrix) writes.
std::vector<ComparisonField> differenceFields(const ImageComparison& r);

/// The per-pixel measures of r in one line of text, e.g. "p99.9 13/255, max 63/255, 1.58% of
/// pixels off by more than 4/255, 3 seams (209 pixels, longest 106), speckle 0.009%".
std::string differenceSummary(const ImageComparison& r);

/// The difference image of compareImages(a, b) for the eye: grey 8 * D (clamped to 255), seam
/// pixels red and speckle pixels yellow. Throws as compareImages does.
Rgb8Image differenceImage(const Rgb8Image& a, const Rgb8Image& b);

}  // namespace uvr

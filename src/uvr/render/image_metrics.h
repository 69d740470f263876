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

/// Similarity of two images of the same size.
struct ImageComparison {
    double ssim = 0.0;            ///< mean SSIM over R, G, B
    double ssimChannel[3] = {};   ///< SSIM per channel
    double psnr = 0.0;            ///< PSNR in dB over all RGB values (infinity when identical)
    double maxAbsDifference = 0;  ///< largest per-value difference (0..255)
};

/// SSIM (Wang et al. 2004: Gaussian window 11x11, sigma 1.5, K1 0.01, K2 0.03, data range 255,
/// population covariances, reflected borders, the 5-pixel border excluded from the mean, as
/// scikit-image's structural_similarity with gaussian_weights=True computes it) and PSNR.
/// Throws Error(Argument) when the sizes differ or an image is smaller than 11x11.
ImageComparison compareImages(const Rgb8Image& a, const Rgb8Image& b);

}  // namespace uvr

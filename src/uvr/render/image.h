// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "uvr/core/vec.h"

namespace uvr {
class OutputFile;
}

namespace uvr {

/// An RGBA float image, row 0 at the top, colours premultiplied by alpha (as front-to-back
/// compositing produces them).
struct Image {
    int width = 0;
    int height = 0;
    std::vector<Vec4f> pixels;  ///< width * height, row-major

    Image() = default;
    Image(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h) {}
    Vec4f& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
    const Vec4f& at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
};

/// Composites one premultiplied pixel over an opaque background and quantises it to 8-bit RGB
/// (each value clamped to [0, 1], NaN to 0, rounded to nearest), exactly as writePng does.
void compositeToRgb8(const Vec4f& pixel, const Vec3f& background, std::uint8_t out[3]);

/// Writes an 8-bit PNG atomically (temporary file, then rename): RGBA with straight (un-
/// premultiplied) colour when background is empty, else RGB composited over the background.
/// Throws Error(Io) naming the file.
void writePng(const std::string& path, const Image& image,
              const std::optional<Vec3f>& background = std::nullopt);

/// Encodes the image as writePng does into an output the caller commits (several outputs of one
/// command can then appear together, after all of them were written).
void writePng(OutputFile& out, const Image& image,
              const std::optional<Vec3f>& background = std::nullopt);

/// The PNG writePng writes, encoded in memory; level is zlib's compression level 0 (fastest) to
/// 9 (smallest), -1 libpng's default.
std::vector<std::uint8_t> encodePng(const Image& image,
                                    const std::optional<Vec3f>& background = std::nullopt,
                                    int level = -1);

/// Reads an 8-bit or 16-bit PNG (grey, grey+alpha, RGB, RGBA, palette) into a premultiplied
/// Image; throws Error(Io/Parse) naming the file.
Image readPng(const std::string& path);

}  // namespace uvr

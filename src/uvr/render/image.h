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

/// The PNG file's 8-bit pixels as writePng makes them, row-major from the top: straight
/// (un-premultiplied) RGBA, 4 bytes a pixel, when background is empty, else RGB composited over
/// the background, 3 bytes a pixel.
std::vector<std::uint8_t> toPngBytes(const Image& image,
                                     const std::optional<Vec3f>& background = std::nullopt);

/// Rows of the strips encodePng deflates at once at level 1.
inline constexpr int kPngStripRows = 128;

/// The PNG writePng writes, encoded in memory; level is zlib's compression level 0 (fastest) to
/// 9 (smallest), -1 libpng's default. Level 1 (the viewer's full frames) filters every row with
/// SUB and, for images of more than kPngStripRows rows, deflates strips of that many rows on the
/// CPU threads into one zlib stream: the same pixels, in a fraction of the time.
std::vector<std::uint8_t> encodePng(const Image& image,
                                    const std::optional<Vec3f>& background = std::nullopt,
                                    int level = -1);

/// An animated PNG (APNG: the PNG extension every current browser, ffmpeg and Pillow read; a
/// plain PNG reader shows its first frame) written frame by frame to `out`: each frame is the
/// PNG encodePng makes of it (libpng, zlib), its image data carried as one frame of the
/// animation, shown for 1/fps seconds, looping. Every frame must have the first's size and the
/// same background (so the same colour type). finish() writes the end; the caller commits `out`.
class ApngWriter {
public:
    /// Starts an animation of frameCount frames (>= 1) at fps (> 0) frames per second.
    ApngWriter(OutputFile& out, int frameCount, double fps);
    /// Appends the next frame; Error(Argument) past frameCount or for another size.
    void add(const Image& image, const std::optional<Vec3f>& background = std::nullopt);
    /// Writes the end; Error(Argument) when fewer than frameCount frames were added.
    void finish();

private:
    void chunk(const char* type, const std::uint8_t* data, std::size_t size);
    OutputFile& out_;
    int frameCount_ = 0, added_ = 0;
    std::uint16_t delayNum_ = 1, delayDen_ = 10;
    std::uint32_t sequence_ = 0;
    int width_ = 0, height_ = 0;
};

/// Reads an 8-bit or 16-bit PNG (grey, grey+alpha, RGB, RGBA, palette) into a premultiplied
/// Image; throws Error(Io/Parse) naming the file.
Image readPng(const std::string& path);

}  // namespace uvr

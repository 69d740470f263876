// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr {

/// True when this build draws text (FreeType and fontconfig were found at configure time, CMake
/// option UVR_ENABLE_TEXT); without them every Font and findFontFile throw Error(Unsupported).
bool textEngineAvailable();

/// The file of the scalable font fontconfig matches to `pattern` (a fontconfig name such as
/// "DejaVu Sans" or "DejaVu Sans:bold"; a system without that family may substitute a similar
/// one). Throws Error(Unsupported) naming the Debian packages to install (fonts-dejavu-core) when
/// fontconfig finds no scalable font at all.
std::string findFontFile(const std::string& pattern = "DejaVu Sans");

/// Vertical metrics of a font at one pixel size, in pixels: y grows downwards, the baseline at 0.
struct FontMetrics {
    float ascender = 0.f;    ///< distance from the baseline up to the top of tall glyphs (> 0)
    float descender = 0.f;   ///< distance from the baseline down to the bottom of descenders (>= 0)
    float lineHeight = 0.f;  ///< baseline-to-baseline distance the font recommends
};

/// A pixel box [x0, x1) x [y0, y1) relative to the pen origin on the baseline (y grows down);
/// empty (x0 >= x1) for a text without ink.
struct TextBox {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x0 >= x1 || y0 >= y1; }
};

/// A scalable font face (TrueType/OpenType) rasterised by FreeType at any pixel size: glyphs
/// anti-aliased (256 grey levels, light hinting), pairs kerned when the face has a kerning table.
/// Text is UTF-8 from anywhere (field names from files): invalid bytes and control characters are
/// drawn as U+FFFD, never refused. Not thread-safe: the face keeps the last pixel size.
class Font {
public:
    /// Loads a font file; throws Error(Io) naming the file when FreeType cannot open it.
    explicit Font(const std::string& path);
    ~Font();
    Font(Font&&) noexcept;
    Font& operator=(Font&&) noexcept;

    /// The font file.
    const std::string& path() const;
    /// The face's family name ("DejaVu Sans").
    std::string familyName() const;
    /// Vertical metrics at a pixel size (the em height, > 0).
    FontMetrics metrics(float pixelSize) const;
    /// Horizontal distance in pixels the pen moves over `text` (kerning included).
    int advance(std::string_view text, float pixelSize) const;
    /// The box of the pixels `text` inks when drawn with its pen origin at (0, 0).
    TextBox inkBox(std::string_view text, float pixelSize) const;
    /// Composites `text` with straight colour `color` and opacity `opacity` over the
    /// premultiplied image, the pen origin at pixel (x, baseline); ink outside the image is
    /// clipped. Returns the advance, as advance() does.
    int draw(Image& image, std::string_view text, float pixelSize, int x, int baseline, Vec3f color,
             float opacity = 1.f) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

/// Composites straight colour `color` with coverage `alpha` in [0, 1] over premultiplied pixel
/// (x, y) of the image ("over"); pixels outside the image are left alone.
inline void blendOver(Image& image, int x, int y, Vec3f color, float alpha) {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height || !(alpha > 0.f)) return;
    if (alpha > 1.f) alpha = 1.f;
    Vec4f& p = image.at(x, y);
    const float keep = 1.f - alpha;
    p = Vec4f{color.x * alpha + p.x * keep, color.y * alpha + p.y * keep,
              color.z * alpha + p.z * keep, alpha + p.w * keep};
}

}  // namespace uvr

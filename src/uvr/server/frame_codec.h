// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr::server {

/// Rows of the strips encodeJpeg encodes at once by default.
inline constexpr int kJpegStripRows = 128;

/// Encodes the image composited over an opaque background as a baseline JPEG (libturbojpeg,
/// 4:2:0 chroma) of the given quality (1-100). An image of more than `stripRows` rows (0:
/// kJpegStripRows; rounded down to a multiple of 16) is encoded in strips of that many rows on
/// the CPU threads and stitched into one JPEG with restart markers between them: the pixels a
/// decoder reads are those of the one-piece encoding, in a fraction of its time (a moving
/// 1024x1024 frame of the viewer). Throws Error(Argument) for a bad quality or an empty image,
/// Error(Resource) when libturbojpeg fails.
std::vector<std::uint8_t> encodeJpeg(const Image& image, Vec3f background, int quality,
                                     int stripRows = 0);

}  // namespace uvr::server

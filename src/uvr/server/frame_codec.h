// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <vector>

#include "uvr/core/vec.h"
#include "uvr/render/image.h"

namespace uvr::server {

/// Encodes the image composited over an opaque background as a baseline JPEG (libturbojpeg,
/// 4:2:0 chroma) of the given quality (1-100); throws Error(Argument) for a bad quality or an
/// empty image, Error(Resource) when libturbojpeg fails.
std::vector<std::uint8_t> encodeJpeg(const Image& image, Vec3f background, int quality);

}  // namespace uvr::server

// SPDX-License-Identifier: MIT
#include "uvr/server/frame_codec.h"

#include <turbojpeg.h>

#include <memory>
#include <string>

#include "uvr/core/error.h"

namespace uvr::server {

std::vector<std::uint8_t> encodeJpeg(const Image& image, Vec3f background, int quality) {
    if (quality < 1 || quality > 100)
        throwError(ErrorKind::Argument, "",
                   "JPEG quality " + std::to_string(quality) + ": expected 1 to 100");
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != static_cast<std::size_t>(image.width) * image.height)
        throwError(ErrorKind::Argument, "", "cannot encode an empty image as JPEG");
    std::vector<std::uint8_t> rgb(image.pixels.size() * 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        compositeToRgb8(image.pixels[i], background, &rgb[3 * i]);
    std::unique_ptr<void, int (*)(tjhandle)> handle(tjInitCompress(), tjDestroy);
    if (!handle) throwError(ErrorKind::Resource, "", "cannot start libturbojpeg's compressor");
    unsigned char* out = nullptr;
    unsigned long size = 0;
    const int rc = tjCompress2(handle.get(), rgb.data(), image.width, 0, image.height, TJPF_RGB,
                               &out, &size, TJSAMP_420, quality, TJFLAG_FASTDCT);
    std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(out, tjFree);
    if (rc != 0)
        throwError(ErrorKind::Resource, "",
                   std::string("JPEG encoding failed: ") + tjGetErrorStr2(handle.get()));
    return std::vector<std::uint8_t>(out, out + size);
}

}  // namespace uvr::server

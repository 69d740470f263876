// SPDX-License-Identifier: MIT
#include "uvr/server/frame_codec.h"

#include <turbojpeg.h>

#include <algorithm>
#include <exception>
#include <memory>
#include <string>

#include "uvr/core/error.h"

namespace uvr::server {

namespace {

/// One JPEG of libturbojpeg, owned.
using TjBytes = std::unique_ptr<unsigned char, void (*)(unsigned char*)>;

/// Encodes rows [y0, y1) of the image over the background as a JPEG of its own.
std::vector<std::uint8_t> encodeRows(const Image& image, Vec3f background, int quality, int y0,
                                     int y1) {
    const std::size_t w = static_cast<std::size_t>(image.width);
    std::vector<std::uint8_t> rgb(w * static_cast<std::size_t>(y1 - y0) * 3);
    for (int y = y0; y < y1; ++y)
        for (std::size_t x = 0; x < w; ++x)
            compositeToRgb8(image.pixels[std::size_t(y) * w + x], background,
                            &rgb[3 * ((std::size_t(y) - y0) * w + x)]);
    std::unique_ptr<void, int (*)(tjhandle)> handle(tjInitCompress(), tjDestroy);
    if (!handle) throwError(ErrorKind::Resource, "", "cannot start libturbojpeg's compressor");
    unsigned char* out = nullptr;
    unsigned long size = 0;
    const int rc = tjCompress2(handle.get(), rgb.data(), image.width, 0, y1 - y0, TJPF_RGB, &out,
                               &size, TJSAMP_420, quality, TJFLAG_FASTDCT);
    TjBytes owned(out, tjFree);
    if (rc != 0)
        throwError(ErrorKind::Resource, "",
                   std::string("JPEG encoding failed: ") + tjGetErrorStr2(handle.get()));
    return std::vector<std::uint8_t>(out, out + size);
}

/// Where the parts of a baseline JPEG of libturbojpeg lie: its SOF0 segment (the frame's size)
/// and its scan (the SOS segment, then the entropy-coded data up to the EOI marker).
struct JpegLayout {
    std::size_t sof = 0;   ///< the SOF0 marker
    std::size_t sos = 0;   ///< the SOS marker
    std::size_t data = 0;  ///< the entropy-coded data (after the SOS segment)
    std::size_t eoi = 0;   ///< the EOI marker
};

JpegLayout layoutOf(const std::vector<std::uint8_t>& j) {
    JpegLayout l;
    std::size_t at = 2;  // after SOI
    while (at + 4 <= j.size() && j[at] == 0xff) {
        const std::uint8_t marker = j[at + 1];
        const std::size_t length = (std::size_t(j[at + 2]) << 8) | j[at + 3];
        if (marker == 0xc0) l.sof = at;
        if (marker == 0xda) {
            l.sos = at;
            l.data = at + 2 + length;
            break;
        }
        at += 2 + length;
    }
    l.eoi = j.size() - 2;
    if (!l.sof || !l.sos || l.data > l.eoi || j[l.eoi] != 0xff || j[l.eoi + 1] != 0xd9)
        throwError(ErrorKind::Internal, "", "libturbojpeg wrote a JPEG of an unexpected layout");
    return l;
}

/// One JPEG of the strips' JPEGs (each of rows a multiple of 16, the last of the rest, all of
/// one quality, so of the same tables): the first's headers with the whole height and a restart
/// interval of one strip's MCUs, then every strip's entropy-coded data, each after the first
/// behind a restart marker. A strip's data begins as a scan after a restart does (DC predictions
/// from zero) and ends padded to a byte, as a restart interval ends: decoders read one image,
/// the pixels of the one-piece encoding.
std::vector<std::uint8_t> stitch(const std::vector<std::vector<std::uint8_t>>& strips, int width,
                                 int height, int stripRows) {
    const JpegLayout first = layoutOf(strips[0]);
    const std::vector<std::uint8_t>& head = strips[0];
    std::vector<std::uint8_t> out(head.begin(), head.begin() + std::ptrdiff_t(first.sos));
    // SOF0: length (2), precision (1), height (2), width (2).
    out[first.sof + 5] = static_cast<std::uint8_t>(height >> 8);
    out[first.sof + 6] = static_cast<std::uint8_t>(height & 0xff);
    const unsigned interval = unsigned((width + 15) / 16) * unsigned(stripRows / 16);
    const std::uint8_t dri[] = {
        0xff, 0xdd, 0x00, 0x04, std::uint8_t(interval >> 8), std::uint8_t(interval & 0xff)};
    out.insert(out.end(), dri, dri + sizeof dri);
    out.insert(out.end(), head.begin() + std::ptrdiff_t(first.sos),
               head.begin() + std::ptrdiff_t(first.data));
    for (std::size_t k = 0; k < strips.size(); ++k) {
        const JpegLayout l = k ? layoutOf(strips[k]) : first;
        if (k) {
            out.push_back(0xff);
            out.push_back(static_cast<std::uint8_t>(0xd0 + (k - 1) % 8));
        }
        out.insert(out.end(), strips[k].begin() + std::ptrdiff_t(l.data),
                   strips[k].begin() + std::ptrdiff_t(l.eoi));
    }
    out.push_back(0xff);
    out.push_back(0xd9);
    return out;
}

}  // namespace

std::vector<std::uint8_t> encodeJpeg(const Image& image, Vec3f background, int quality,
                                     int stripRows) {
    if (quality < 1 || quality > 100)
        throwError(ErrorKind::Argument, "",
                   "JPEG quality " + std::to_string(quality) + ": expected 1 to 100");
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != static_cast<std::size_t>(image.width) * image.height)
        throwError(ErrorKind::Argument, "", "cannot encode an empty image as JPEG");
    if (stripRows == 0) stripRows = kJpegStripRows;
    // Whole MCU rows, and a restart interval a 16-bit count holds.
    stripRows = std::max(16, stripRows / 16 * 16);
    stripRows = std::min(stripRows, 65535 / ((image.width + 15) / 16) * 16);
    if (stripRows < 16 || image.height <= stripRows)
        return encodeRows(image, background, quality, 0, image.height);
    const int count = (image.height + stripRows - 1) / stripRows;
    std::vector<std::vector<std::uint8_t>> strips(static_cast<std::size_t>(count));
    std::exception_ptr failed;
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < count; ++k) {
        try {
            strips[std::size_t(k)] = encodeRows(image, background, quality, k * stripRows,
                                                std::min(image.height, (k + 1) * stripRows));
        } catch (...) {
#pragma omp critical(uvr_jpeg_strips)
            failed = std::current_exception();
        }
    }
    if (failed) std::rethrow_exception(failed);
    return stitch(strips, image.width, image.height, stripRows);
}

}  // namespace uvr::server

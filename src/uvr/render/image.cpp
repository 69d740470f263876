// SPDX-License-Identifier: MIT
#include "uvr/render/image.h"

#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"

namespace uvr {

namespace {

/// Largest decoded image accepted by readPng, in bytes (float pixels plus decoded rows).
constexpr std::uint64_t kMaxDecodedBytes = 4ull << 30;

/// libpng error state: the first message, reported after longjmp back to the caller.
struct PngErrorState {
    char message[256] = {0};
};

void pngError(png_structp png, png_const_charp msg) {
    auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
    if (state && state->message[0] == '\0') {
        std::snprintf(state->message, sizeof(state->message), "%s", msg ? msg : "libpng error");
    }
    png_longjmp(png, 1);
}

void pngWarning(png_structp, png_const_charp) {}

/// In-memory source for libpng reads.
struct PngSource {
    const unsigned char* data = nullptr;
    size_t size = 0;
    size_t pos = 0;
};

void readFromMemory(png_structp png, png_bytep out, png_size_t count) {
    auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
    if (count > src->size - src->pos) png_error(png, "unexpected end of file");
    std::memcpy(out, src->data + src->pos, count);
    src->pos += count;
}

std::uint8_t toByte(float v) {
    v = v > 0.f ? (v < 1.f ? v : 1.f) : 0.f;  // NaN becomes 0
    // Round to nearest, halves up (as lround for these non-negative values), without a libm
    // call: encoding a 1024x1024 frame's pixels took 7 ms through lround, 1 ms like this.
    return static_cast<std::uint8_t>(v * 255.f + 0.5f);
}

/// Where encodePng's bytes go: an output file or memory, with the first failure kept for
/// rethrowing; the zlib level (-1: libpng's default).
struct PngSink {
    OutputFile* out = nullptr;
    std::vector<std::uint8_t>* memory = nullptr;
    int level = -1;
    std::exception_ptr failure;
};

/// libpng's write callback: bytes into the output; a failure is kept and ends the encoding.
void writeToSink(png_structp png, png_bytep data, png_size_t count) {
    auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
    bool failed = false;
    try {
        if (sink->out)
            sink->out->write(data, count);
        else
            sink->memory->insert(sink->memory->end(), data, data + count);
    } catch (...) {
        sink->failure = std::current_exception();
        failed = true;
    }
    if (failed) png_error(png, "write failed");  // longjmp: no C++ object is alive here
}

void flushSink(png_structp) {}

/// libpng write with setjmp error handling; no C++ objects live in this frame. Returns false
/// with state.message set on failure.
bool encodePng(PngSink& sink, int width, int height, bool alpha, png_bytep* rows,
               PngErrorState& state) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, pngError, pngWarning);
    if (!png) {
        std::snprintf(state.message, sizeof(state.message), "cannot create a PNG writer");
        return false;
    }
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        if (state.message[0] == '\0')
            std::snprintf(state.message, sizeof(state.message), "cannot create PNG info");
        png_destroy_write_struct(&png, info ? &info : nullptr);
        return false;
    }
    png_set_write_fn(png, &sink, writeToSink, flushSink);
    if (sink.level >= 0) png_set_compression_level(png, sink.level);
    if (sink.level == 1) {
        // The fastest lossless setting for frames sent while someone waits: one cheap filter
        // instead of libpng's per-row choice among five, and run-length matching.
        png_set_filter(png, 0, PNG_FILTER_SUB);
        png_set_compression_strategy(png, Z_RLE);
    }
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
                 alpha ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return true;
}

/// Image size and sample depth after the conversion to RGBA.
struct PngHeader {
    png_uint_32 width = 0, height = 0;
    int bitDepth = 0;
    size_t rowBytes = 0;
};

/// Reads the header and sets transformations to RGBA (8 or 16 bits per channel, big-endian).
bool decodeHeader(png_structp png, png_infop info, PngHeader& header) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_read_info(png, info);
    int colorType = png_get_color_type(png, info);
    int bitDepth = png_get_bit_depth(png, info);
    if (colorType == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (colorType == PNG_COLOR_TYPE_GRAY && bitDepth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    if (colorType == PNG_COLOR_TYPE_GRAY || colorType == PNG_COLOR_TYPE_GRAY_ALPHA)
        png_set_gray_to_rgb(png);
    if (!(colorType & PNG_COLOR_MASK_ALPHA) && !png_get_valid(png, info, PNG_INFO_tRNS))
        png_set_add_alpha(png, 0xffff, PNG_FILLER_AFTER);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    header.width = png_get_image_width(png, info);
    header.height = png_get_image_height(png, info);
    header.bitDepth = png_get_bit_depth(png, info);
    header.rowBytes = png_get_rowbytes(png, info);
    return true;
}

bool decodeRows(png_structp png, png_infop info, png_bytep* rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_read_image(png, rows);
    png_read_end(png, nullptr);
    (void)info;
    return true;
}

/// Owns a libpng read struct.
struct PngReader {
    png_structp png = nullptr;
    png_infop info = nullptr;
    ~PngReader() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

}  // namespace

void compositeToRgb8(const Vec4f& pixel, const Vec3f& background, std::uint8_t out[3]) {
    const float a = pixel.w > 0.f ? (pixel.w < 1.f ? pixel.w : 1.f) : 0.f;
    const Vec3f c = pixel.xyz() + background * (1.f - a);
    out[0] = toByte(c.x);
    out[1] = toByte(c.y);
    out[2] = toByte(c.z);
}

void writePng(const std::string& path, const Image& image, const std::optional<Vec3f>& background) {
    OutputFile out(path);
    writePng(out, image, background);
    out.commit();
}

std::vector<std::uint8_t> toPngBytes(const Image& image, const std::optional<Vec3f>& background) {
    const bool alpha = !background.has_value();
    const size_t channels = alpha ? 4 : 3;
    std::vector<std::uint8_t> bytes(image.pixels.size() * channels);
#pragma omp parallel for schedule(static) if (image.pixels.size() >= (1u << 16))
    for (std::int64_t i = 0; i < std::int64_t(image.pixels.size()); ++i) {
        Vec4f p = image.pixels[std::size_t(i)];
        std::uint8_t* px = &bytes[i * channels];
        if (alpha) {
            float inv = p.w > 0.f ? 1.f / p.w : 0.f;
            px[0] = toByte(p.x * inv);
            px[1] = toByte(p.y * inv);
            px[2] = toByte(p.z * inv);
            px[3] = toByte(p.w);
        } else {
            compositeToRgb8(p, *background, px);
        }
    }
    return bytes;
}

namespace {

/// Encodes the image as 8-bit PNG rows into the sink: straight RGBA, or RGB composited over the
/// background. `what` names the destination in errors.
void encodeImage(PngSink& sink, const std::string& what, const Image& image,
                 const std::optional<Vec3f>& background) {
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != static_cast<size_t>(image.width) * image.height) {
        throwError(ErrorKind::Argument, what,
                   "cannot write a " + std::to_string(image.width) + " x " +
                       std::to_string(image.height) + " image with " +
                       std::to_string(image.pixels.size()) + " pixels as PNG");
    }
    // Convert to 8-bit rows: straight RGBA, or RGB composited over the background.
    const bool alpha = !background.has_value();
    const size_t channels = alpha ? 4 : 3;
    std::vector<std::uint8_t> bytes = toPngBytes(image, background);
    std::vector<png_bytep> rows(static_cast<size_t>(image.height));
    for (int y = 0; y < image.height; ++y)
        rows[y] = &bytes[static_cast<size_t>(y) * image.width * channels];

    PngErrorState state;
    const bool ok = encodePng(sink, image.width, image.height, alpha, rows.data(), state);
    if (sink.failure) std::rethrow_exception(sink.failure);
    if (!ok) throwError(ErrorKind::Io, what, std::string("PNG write failed: ") + state.message);
}

}  // namespace

void writePng(OutputFile& out, const Image& image, const std::optional<Vec3f>& background) {
    PngSink sink;
    sink.out = &out;
    encodeImage(sink, out.path(), image, background);
}

namespace {

void putU32(std::vector<std::uint8_t>& v, std::uint32_t x) {
    for (int s = 24; s >= 0; s -= 8) v.push_back(static_cast<std::uint8_t>(x >> s));
}

void putU16(std::vector<std::uint8_t>& v, std::uint16_t x) {
    v.push_back(static_cast<std::uint8_t>(x >> 8));
    v.push_back(static_cast<std::uint8_t>(x));
}

std::uint32_t getU32(const std::uint8_t* p) {
    return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
           std::uint32_t(p[3]);
}

/// Appends a PNG chunk (length, type, data, CRC) to `out`.
void appendChunk(std::vector<std::uint8_t>& out, const char* type, const std::uint8_t* data,
                 std::size_t size) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(size >> (24 - 8 * k)));
    const std::size_t at = out.size();
    out.insert(out.end(), type, type + 4);
    if (size > 0) out.insert(out.end(), data, data + size);
    const uLong crc = crc32(0L, out.data() + at, static_cast<uInt>(4 + size));
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(crc >> (24 - 8 * k)));
}

/// encodePng at level 1 of an image of more than kPngStripRows rows: each row SUB-filtered (the
/// filter libpng is told to use at that level), the rows deflated by zlib (level 1, run-length
/// matching, as there) in strips of kPngStripRows on the CPU threads and joined into one zlib
/// stream, as pigz joins its blocks: every strip but the last ends on a sync flush (a byte
/// boundary, no final block), and the stream's Adler-32 is combined from the strips'. One IDAT.
std::vector<std::uint8_t> encodePngInStrips(const Image& image,
                                            const std::optional<Vec3f>& background) {
    const bool alpha = !background.has_value();
    const std::size_t channels = alpha ? 4 : 3;
    const std::size_t row = static_cast<std::size_t>(image.width) * channels;
    const std::vector<std::uint8_t> bytes = toPngBytes(image, background);
    const int strips = (image.height + kPngStripRows - 1) / kPngStripRows;
    std::vector<std::vector<std::uint8_t>> packed(static_cast<std::size_t>(strips));
    std::vector<uLong> adlers(static_cast<std::size_t>(strips));
    std::vector<std::size_t> lengths(static_cast<std::size_t>(strips));
    std::vector<int> failures(static_cast<std::size_t>(strips), Z_OK);
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < strips; ++k) {
        const int y0 = k * kPngStripRows, y1 = std::min(image.height, y0 + kPngStripRows);
        std::vector<std::uint8_t> filtered(std::size_t(y1 - y0) * (row + 1));
        for (int y = y0; y < y1; ++y) {
            const std::uint8_t* in = &bytes[std::size_t(y) * row];
            std::uint8_t* out = &filtered[std::size_t(y - y0) * (row + 1)];
            out[0] = 1;  // SUB: each byte less the one a pixel to its left
            for (std::size_t i = 0; i < row; ++i)
                out[1 + i] =
                    static_cast<std::uint8_t>(in[i] - (i >= channels ? in[i - channels] : 0));
        }
        const std::size_t at = static_cast<std::size_t>(k);
        adlers[at] = adler32(1L, filtered.data(), static_cast<uInt>(filtered.size()));
        lengths[at] = filtered.size();
        z_stream z{};
        int rc = deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_RLE);  // raw: no header, no trailer
        if (rc == Z_OK) {
            packed[at].resize(deflateBound(&z, static_cast<uLong>(filtered.size())) + 16);
            z.next_in = filtered.data();
            z.avail_in = static_cast<uInt>(filtered.size());
            z.next_out = packed[at].data();
            z.avail_out = static_cast<uInt>(packed[at].size());
            rc = deflate(&z, k + 1 == strips ? Z_FINISH : Z_SYNC_FLUSH);
            const bool done = k + 1 == strips ? rc == Z_STREAM_END : rc == Z_OK && z.avail_in == 0;
            packed[at].resize(z.total_out);
            deflateEnd(&z);
            rc = done ? Z_OK : Z_BUF_ERROR;
        }
        failures[at] = rc;
    }
    for (const int rc : failures)
        if (rc != Z_OK)
            throwError(ErrorKind::Resource, "",
                       "PNG compression failed: zlib error " + std::to_string(rc));
    std::vector<std::uint8_t> out = {137, 80, 78, 71, 13, 10, 26, 10};
    std::vector<std::uint8_t> header;
    putU32(header, static_cast<std::uint32_t>(image.width));
    putU32(header, static_cast<std::uint32_t>(image.height));
    header.insert(header.end(), {8, std::uint8_t(alpha ? 6 : 2), 0, 0, 0});
    appendChunk(out, "IHDR", header.data(), header.size());
    std::vector<std::uint8_t> data = {0x78, 0x01};  // zlib: deflate, 32 KiB window, level 1
    uLong adler = adlers[0];
    for (std::size_t k = 0; k < packed.size(); ++k) {
        data.insert(data.end(), packed[k].begin(), packed[k].end());
        if (k) adler = adler32_combine(adler, adlers[k], static_cast<z_off_t>(lengths[k]));
    }
    putU32(data, static_cast<std::uint32_t>(adler));
    appendChunk(out, "IDAT", data.data(), data.size());
    appendChunk(out, "IEND", nullptr, 0);
    return out;
}

}  // namespace

std::vector<std::uint8_t> encodePng(const Image& image, const std::optional<Vec3f>& background,
                                    int level) {
    if (level < -1 || level > 9)
        throwError(ErrorKind::Argument, "",
                   "PNG compression level " + std::to_string(level) + ": expected -1 to 9");
    if (level == 1 && image.height > kPngStripRows && image.width > 0 &&
        image.pixels.size() == static_cast<size_t>(image.width) * image.height)
        return encodePngInStrips(image, background);
    std::vector<std::uint8_t> bytes;
    PngSink sink;
    sink.memory = &bytes;
    sink.level = level;
    encodeImage(sink, "PNG in memory", image, background);
    return bytes;
}

ApngWriter::ApngWriter(OutputFile& out, int frameCount, double fps)
    : out_(out), frameCount_(frameCount) {
    if (frameCount < 1)
        throwError(ErrorKind::Argument, out.path(),
                   "an animation needs at least one frame, not " + std::to_string(frameCount));
    if (!(fps > 0.0 && fps <= 1000.0))
        throwError(ErrorKind::Argument, out.path(),
                   "frames per second must lie in (0, 1000], not " + std::to_string(fps));
    // The delay as a fraction num / den seconds: 1 / fps for whole fps, else in milliseconds.
    if (std::fabs(fps - std::round(fps)) < 1e-9 && fps <= 65535.0) {
        delayNum_ = 1, delayDen_ = static_cast<std::uint16_t>(std::round(fps));
    } else {
        delayNum_ = static_cast<std::uint16_t>(std::clamp(std::round(1000.0 / fps), 1.0, 65535.0));
        delayDen_ = 1000;
    }
}

void ApngWriter::chunk(const char* type, const std::uint8_t* data, std::size_t size) {
    std::vector<std::uint8_t> bytes;
    bytes.reserve(size + 12);
    appendChunk(bytes, type, data, size);
    out_.write(bytes.data(), bytes.size());
}

void ApngWriter::add(const Image& image, const std::optional<Vec3f>& background) {
    if (added_ >= frameCount_)
        throwError(ErrorKind::Argument, out_.path(),
                   "more frames than the " + std::to_string(frameCount_) + " announced");
    if (added_ > 0 && (image.width != width_ || image.height != height_))
        throwError(ErrorKind::Argument, out_.path(),
                   "frame " + std::to_string(added_) + " is " + std::to_string(image.width) + "x" +
                       std::to_string(image.height) + ", the first " + std::to_string(width_) +
                       "x" + std::to_string(height_));
    const std::vector<std::uint8_t> png = encodePng(image, background);
    // The PNG's chunks after its signature: IHDR first, then IDATs (libpng writes no others
    // between them that a frame needs).
    std::size_t at = 8;
    bool first = added_ == 0;
    if (first) {
        static const std::uint8_t kSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
        out_.write(kSignature, sizeof kSignature);
        width_ = image.width, height_ = image.height;
    }
    std::vector<std::uint8_t> control;  // fcTL
    putU32(control, sequence_++);
    putU32(control, static_cast<std::uint32_t>(image.width));
    putU32(control, static_cast<std::uint32_t>(image.height));
    putU32(control, 0);
    putU32(control, 0);
    putU16(control, delayNum_);
    putU16(control, delayDen_);
    control.push_back(0);  // dispose: none
    control.push_back(0);  // blend: source (each frame replaces the last)
    bool controlWritten = false;
    while (at + 12 <= png.size()) {
        const std::uint32_t length = getU32(&png[at]);
        const char* type = reinterpret_cast<const char*>(&png[at + 4]);
        const std::uint8_t* data = &png[at + 8];
        if (at + 12 + length > png.size()) break;
        const std::string name(type, 4);
        if (name == "IHDR" && first) {
            chunk("IHDR", data, length);
            std::vector<std::uint8_t> actl;
            putU32(actl, static_cast<std::uint32_t>(frameCount_));
            putU32(actl, 0);  // loop for ever
            chunk("acTL", actl.data(), actl.size());
        } else if (name == "IDAT") {
            if (!controlWritten) chunk("fcTL", control.data(), control.size());
            controlWritten = true;
            if (first) {
                chunk("IDAT", data, length);
            } else {
                std::vector<std::uint8_t> fdat;
                putU32(fdat, sequence_++);
                fdat.insert(fdat.end(), data, data + length);
                chunk("fdAT", fdat.data(), fdat.size());
            }
        }
        at += 12 + length;
    }
    ++added_;
}

void ApngWriter::finish() {
    if (added_ != frameCount_)
        throwError(ErrorKind::Argument, out_.path(),
                   std::to_string(added_) + " frames added of the " + std::to_string(frameCount_) +
                       " announced");
    chunk("IEND", nullptr, 0);
}

Image readPng(const std::string& path) {
    std::vector<char> file = readFileBytes(path);
    if (file.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(file.data()), 0, 8)) {
        throwParseError(path, atByte(0), "expected the PNG signature, got something else");
    }
    PngSource source{reinterpret_cast<const unsigned char*>(file.data()), file.size(), 0};
    PngErrorState state;
    PngReader reader;
    reader.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, pngError, pngWarning);
    if (reader.png) reader.info = png_create_info_struct(reader.png);
    if (!reader.png || !reader.info)
        throwError(ErrorKind::Resource, path, "cannot create a PNG reader");
    png_set_read_fn(reader.png, &source, readFromMemory);

    // Step 1: header, and a size check before allocating.
    PngHeader header;
    if (!decodeHeader(reader.png, reader.info, header)) {
        throwParseError(path, atByte(source.pos),
                        std::string("expected a valid PNG header, got: ") + state.message);
    }
    std::uint64_t pixelCount = static_cast<std::uint64_t>(header.width) * header.height;
    checkAllocation(path, "PNG pixels", pixelCount, sizeof(Vec4f) + 8, kMaxDecodedBytes);
    const int channelBytes = header.bitDepth == 16 ? 2 : 1;
    if (header.rowBytes != static_cast<size_t>(header.width) * 4 * channelBytes) {
        throwError(ErrorKind::Internal, path, "unexpected PNG row size after conversion to RGBA");
    }

    // Step 2: pixel rows.
    std::vector<std::uint8_t> bytes(header.rowBytes * header.height);
    std::vector<png_bytep> rows(header.height);
    for (png_uint_32 y = 0; y < header.height; ++y) rows[y] = &bytes[y * header.rowBytes];
    if (!decodeRows(reader.png, reader.info, rows.data())) {
        throwParseError(path, atByte(source.pos),
                        std::string("truncated or corrupt PNG data: ") + state.message);
    }

    // Step 3: to premultiplied float RGBA.
    Image image(static_cast<int>(header.width), static_cast<int>(header.height));
    const float scale = header.bitDepth == 16 ? 1.f / 65535.f : 1.f / 255.f;
    for (size_t i = 0; i < image.pixels.size(); ++i) {
        const std::uint8_t* p = &bytes[i * 4 * channelBytes];
        float c[4];
        for (int k = 0; k < 4; ++k) {
            unsigned v = channelBytes == 2 ? (p[2 * k] << 8) | p[2 * k + 1] : p[k];
            c[k] = static_cast<float>(v) * scale;
        }
        image.pixels[i] = Vec4f(c[0] * c[3], c[1] * c[3], c[2] * c[3], c[3]);
    }
    return image;
}

}  // namespace uvr

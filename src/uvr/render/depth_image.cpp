// SPDX-License-Identifier: MIT
#include "uvr/render/depth_image.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <regex>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"

namespace uvr {

namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicBytes = 6;

[[noreturn]] void bad(const std::string& path, const std::string& what) {
    throwError(ErrorKind::Parse, path, "not a depth image: " + what);
}

}  // namespace

void writeDepthNpy(OutputFile& out, int width, int height, const std::vector<float>& depth) {
    if (width <= 0 || height <= 0 || depth.size() != std::size_t(width) * std::size_t(height))
        throwError(ErrorKind::Internal, out.path(), "depth image of the wrong size");
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                         std::to_string(height) + ", " + std::to_string(width) + "), }";
    // Magic, version 1.0, header length; the header padded with spaces to a multiple of 64
    // bytes in all and ended by a newline.
    const std::size_t preamble = kMagicBytes + 2 + 2;
    const std::size_t total = (preamble + header.size() + 1 + 63) / 64 * 64;
    header.append(total - preamble - header.size() - 1, ' ');
    header += '\n';
    const std::uint16_t length = static_cast<std::uint16_t>(header.size());
    const unsigned char pre[preamble] = {0x93,
                                         'N',
                                         'U',
                                         'M',
                                         'P',
                                         'Y',
                                         1,
                                         0,
                                         static_cast<unsigned char>(length & 0xff),
                                         static_cast<unsigned char>(length >> 8)};
    out.write(pre, preamble);
    out.write(header);
    out.write(depth.data(), depth.size() * sizeof(float));  // x86-64 and aarch64: little-endian
}

std::vector<float> readDepthNpy(const std::string& path, int width, int height) {
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    // The header first (at most 64 KiB), so that a file of another shape is named as such.
    checkRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throwError(ErrorKind::Io, path, "cannot open the depth image");
    std::vector<char> bytes(65536);
    in.read(bytes.data(), std::streamsize(bytes.size()));
    bytes.resize(std::size_t(in.gcount()));
    if (bytes.size() < kMagicBytes + 4 || std::memcmp(bytes.data(), kMagic, kMagicBytes) != 0)
        bad(path, "its first bytes are not a NumPy .npy file's (save one with numpy.save)");
    const int major = static_cast<unsigned char>(bytes[6]);
    std::size_t headerLength, start;
    if (major == 1) {
        headerLength = static_cast<unsigned char>(bytes[8]) |
                       (std::size_t(static_cast<unsigned char>(bytes[9])) << 8);
        start = 10;
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) bad(path, "truncated header");
        headerLength = 0;
        for (int i = 0; i < 4; ++i)
            headerLength |= std::size_t(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
        start = 12;
    } else {
        bad(path, ".npy format version " + std::to_string(major) + " (1, 2 or 3 are read)");
    }
    if (start + headerLength > bytes.size()) bad(path, "truncated header");
    const std::string header(bytes.data() + start, headerLength);
    std::smatch m;
    static const std::regex descr(R"('descr'\s*:\s*'([<>|=]?)([a-z])(\d+)')");
    static const std::regex order(R"('fortran_order'\s*:\s*(True|False))");
    static const std::regex shape(R"('shape'\s*:\s*\(\s*(\d+)\s*,\s*(\d+)\s*,?\s*\))");
    if (!std::regex_search(header, m, descr)) bad(path, "no dtype in its header");
    const std::string type = m[2].str() + m[3].str();
    if (m[1] == ">" || (type != "f4" && type != "f8"))
        bad(path, "dtype '" + m[1].str() + type +
                      "': expected little-endian float32 ('<f4') or float64 ('<f8')");
    const std::size_t size = type == "f4" ? 4 : 8;
    if (!std::regex_search(header, m, order) || m[1] == "True")
        bad(path, "not in C order (fortran_order must be False)");
    if (!std::regex_search(header, m, shape))
        bad(path, "its shape is not (height, width): a 2-D array is expected");
    if (m[1].str() != std::to_string(height) || m[2].str() != std::to_string(width))
        bad(path, "shape (" + m[1].str() + ", " + m[2].str() + "), but the frame is " +
                      std::to_string(width) + "x" + std::to_string(height) + ": expected (" +
                      std::to_string(height) + ", " + std::to_string(width) + ")");
    const std::size_t data = start + headerLength;
    in.clear();
    in.seekg(0, std::ios::end);
    const std::size_t fileBytes = std::size_t(in.tellg());
    if (fileBytes != data + pixels * size)
        bad(path, std::to_string(fileBytes - data) + " bytes of data, expected " +
                      std::to_string(pixels * size) + " (truncated or padded)");
    std::vector<char> values(pixels * size);
    in.seekg(std::streamoff(data));
    in.read(values.data(), std::streamsize(values.size()));
    if (std::size_t(in.gcount()) != values.size())
        throwError(ErrorKind::Io, path, "could not read the depth image's values");
    std::vector<float> out(pixels);
    if (size == 4) {
        std::memcpy(out.data(), values.data(), pixels * 4);
    } else {
        for (std::size_t i = 0; i < pixels; ++i) {
            double v;
            std::memcpy(&v, values.data() + 8 * i, 8);
            out[i] = static_cast<float>(v);
        }
    }
    return out;
}

}  // namespace uvr

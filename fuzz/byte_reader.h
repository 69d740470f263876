// SPDX-License-Identifier: MIT
#pragma once

// The fuzz targets' reader of their input bytes (the structured targets build files from them).

#include <cstdint>
#include <cstring>

namespace uvr::fuzz {

/// Reads the input: bytes in order, then zeros once they run out.
class ByteReader {
public:
    ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
    std::uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
    /// A small count, usually the intended one, sometimes off by a signed byte (or absurd).
    std::int64_t count(std::int64_t intended) {
        const std::uint8_t b = byte();
        if (b < 224) return intended;
        if (b == 255) return std::int64_t(1) << 40;
        return intended + static_cast<std::int8_t>(byte());
    }
    /// Four bytes as a float, any bit pattern.
    float real() {
        std::uint8_t b[4] = {byte(), byte(), byte(), byte()};
        float v;
        std::memcpy(&v, b, sizeof v);
        return v;
    }

private:
    const std::uint8_t* data_;
    std::size_t size_;
    std::size_t pos_ = 0;
};

}  // namespace uvr::fuzz

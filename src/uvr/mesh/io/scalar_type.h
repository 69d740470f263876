// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>

namespace uvr {

/// Numeric element types found in VTK files.
enum class ScalarType : std::uint8_t {
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Float32,
    Float64
};

/// Size of one element in bytes.
constexpr std::size_t scalarSize(ScalarType t) {
    switch (t) {
        case ScalarType::Int8:
        case ScalarType::UInt8:
            return 1;
        case ScalarType::Int16:
        case ScalarType::UInt16:
            return 2;
        case ScalarType::Int32:
        case ScalarType::UInt32:
        case ScalarType::Float32:
            return 4;
        case ScalarType::Int64:
        case ScalarType::UInt64:
        case ScalarType::Float64:
            return 8;
    }
    return 0;
}

/// True for the integer types.
constexpr bool isIntegerType(ScalarType t) {
    return t != ScalarType::Float32 && t != ScalarType::Float64;
}

/// Parses a legacy-VTK type name (unsigned_char, int, float, vtktypeint64, vtkIdType, ...); "long"
/// is 64-bit, as VTK writes it on LP64 systems.
std::optional<ScalarType> parseLegacyTypeName(const std::string& name);
/// Parses a VTK XML type name (Int8 ... Float64, plus "Int" / "Float" spellings are not accepted).
std::optional<ScalarType> parseXmlTypeName(const std::string& name);
/// The VTK XML name of a type ("Float32").
const char* xmlTypeName(ScalarType t);

/// Copies element i of raw bytes of type t into buf in host order (reversing the bytes when
/// swap).
inline void loadElementBytes(const unsigned char* data, ScalarType t, std::size_t i, bool swap,
                             unsigned char buf[8]) {
    const std::size_t n = scalarSize(t);
    if (n > 8) return;  // never: tells the compiler buf cannot overflow
    const unsigned char* src = data + i * n;
    if (swap) {
        for (std::size_t k = 0; k < n; ++k) buf[k] = src[n - 1 - k];
    } else {
        std::memcpy(buf, src, n);
    }
}

/// Reads element i of raw bytes of type t (swapping bytes when swap) as double.
inline double loadAsDouble(const unsigned char* data, ScalarType t, std::size_t i, bool swap) {
    unsigned char buf[8] = {};
    loadElementBytes(data, t, i, swap, buf);
    switch (t) {
        case ScalarType::Int8: {
            std::int8_t v;
            std::memcpy(&v, buf, 1);
            return v;
        }
        case ScalarType::UInt8:
            return buf[0];
        case ScalarType::Int16: {
            std::int16_t v;
            std::memcpy(&v, buf, 2);
            return v;
        }
        case ScalarType::UInt16: {
            std::uint16_t v;
            std::memcpy(&v, buf, 2);
            return v;
        }
        case ScalarType::Int32: {
            std::int32_t v;
            std::memcpy(&v, buf, 4);
            return v;
        }
        case ScalarType::UInt32: {
            std::uint32_t v;
            std::memcpy(&v, buf, 4);
            return v;
        }
        case ScalarType::Int64: {
            std::int64_t v;
            std::memcpy(&v, buf, 8);
            return static_cast<double>(v);
        }
        case ScalarType::UInt64: {
            std::uint64_t v;
            std::memcpy(&v, buf, 8);
            return static_cast<double>(v);
        }
        case ScalarType::Float32: {
            float v;
            std::memcpy(&v, buf, 4);
            return v;
        }
        case ScalarType::Float64: {
            double v;
            std::memcpy(&v, buf, 8);
            return v;
        }
    }
    return 0.0;
}

/// Reads element i of raw bytes of integer type t as int64 exactly (UInt64 above INT64_MAX wraps
/// negative, which range checks then reject).
inline std::int64_t loadAsInt64(const unsigned char* data, ScalarType t, std::size_t i, bool swap) {
    unsigned char buf[8] = {};
    loadElementBytes(data, t, i, swap, buf);
    switch (t) {
        case ScalarType::Int64: {
            std::int64_t v;
            std::memcpy(&v, buf, 8);
            return v;
        }
        case ScalarType::UInt64: {
            std::uint64_t v;
            std::memcpy(&v, buf, 8);
            return static_cast<std::int64_t>(v);
        }
        case ScalarType::Float32:
        case ScalarType::Float64: {
            double d = loadAsDouble(data, t, i, swap);
            return (d >= -9.2e18 && d <= 9.2e18) ? static_cast<std::int64_t>(d) : -1;
        }
        default:
            return static_cast<std::int64_t>(loadAsDouble(data, t, i, swap));
    }
}

/// True when this machine is little-endian.
inline bool hostIsLittleEndian() {
    const std::uint16_t one = 1;
    unsigned char b;
    std::memcpy(&b, &one, 1);
    return b == 1;
}

}  // namespace uvr

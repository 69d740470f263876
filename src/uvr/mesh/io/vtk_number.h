// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace uvr {

// Numbers as VTK's readers take them (vtkXMLDataElement attributes, vtkXMLDataParser's ASCII data,
// vtkDataReader's legacy tokens: C++ stream extraction, plus "nan"/"inf" in XML ASCII data):
// leading and trailing whitespace, an optional '+' or '-', decimal digits (leading zeros are
// decimal, not octal), and for reals a fraction and an exponent (1e3, 1E+03, .5, 5.). Not
// accepted, because VTK reads them as something else or not at all: hexadecimal (0x10 reads as
// 0), Fortran exponents (1.5d0), decimal commas, trailing garbage (4abc).

/// Parses a real number: decimal with optional fraction and exponent, or nan/inf/infinity in any
/// case with an optional sign; out-of-range magnitudes become +-inf or 0 as strtod gives them.
std::optional<double> parseVtkReal(std::string_view text);

/// Parses an integer; a real form with an integral value in the int64 range ("4.0", "1e3") is
/// accepted too, as VTK's XML attributes accept it; anything else (fractions, nan) is refused.
std::optional<std::int64_t> parseVtkInteger(std::string_view text);

/// Parses a non-negative integer as parseVtkInteger does (a leading '+' allowed, '-' refused
/// except for "-0"), up to 2^64 - 1.
std::optional<std::uint64_t> parseVtkCount(std::string_view text);

}  // namespace uvr

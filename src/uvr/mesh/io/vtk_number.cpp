// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_number.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>

namespace uvr {

namespace {

bool isVtkSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && isVtkSpace(s.front())) s.remove_prefix(1);
    while (!s.empty() && isVtkSpace(s.back())) s.remove_suffix(1);
    return s;
}

/// Removes a leading '+' (from_chars takes only '-'); "+-1" and "+" stay invalid.
std::string_view dropPlus(std::string_view s) {
    if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
    return s;
}

/// True when s has the shape of a decimal real (sign, digits, '.', exponent) with a digit.
bool isDecimalReal(std::string_view s) {
    std::size_t i = 0;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    bool digits = false;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, digits = true;
    if (i < s.size() && s[i] == '.') {
        ++i;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, digits = true;
    }
    if (!digits) return false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
        bool expDigits = false;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, expDigits = true;
        if (!expDigits) return false;
    }
    return i == s.size();
}

}  // namespace

std::optional<double> parseVtkReal(std::string_view text) {
    const std::string_view s = dropPlus(trim(text));
    if (s.empty()) return std::nullopt;
    double v = 0.0;
    const char* end = s.data() + s.size();
    const auto r = std::from_chars(s.data(), end, v, std::chars_format::general);
    if (r.ptr != end) return std::nullopt;
    if (r.ec == std::errc()) return v;
    if (r.ec == std::errc::result_out_of_range) return std::strtod(std::string(s).c_str(), nullptr);
    return std::nullopt;
}

std::optional<std::int64_t> parseVtkInteger(std::string_view text) {
    const std::string_view s = dropPlus(trim(text));
    if (s.empty()) return std::nullopt;
    std::int64_t v = 0;
    const char* end = s.data() + s.size();
    const auto r = std::from_chars(s.data(), end, v);
    if (r.ptr == end && r.ec == std::errc()) return v;
    if (r.ptr == end) return std::nullopt;  // all digits, out of range
    // A real form of an integral value ("4.0", "1e3"), never nan, inf or hexadecimal.
    if (!isDecimalReal(s)) return std::nullopt;
    const std::optional<double> d = parseVtkReal(s);
    if (!d || std::trunc(*d) != *d || *d < -9.2e18 || *d > 9.2e18) return std::nullopt;
    return static_cast<std::int64_t>(*d);
}

std::optional<std::uint64_t> parseVtkCount(std::string_view text) {
    const std::string_view s = dropPlus(trim(text));
    if (s.empty()) return std::nullopt;
    std::uint64_t v = 0;
    const char* end = s.data() + s.size();
    if (s.front() != '-') {
        const auto r = std::from_chars(s.data(), end, v);
        if (r.ptr == end && r.ec == std::errc()) return v;
        if (r.ptr == end) return std::nullopt;  // all digits, out of range
    }
    const std::optional<std::int64_t> i = parseVtkInteger(s);
    if (!i || *i < 0) return std::nullopt;
    return static_cast<std::uint64_t>(*i);
}

}  // namespace uvr

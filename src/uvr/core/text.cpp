// SPDX-License-Identifier: MIT
#include "uvr/core/text.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstdio>

namespace uvr {

namespace {

/// Length of the valid UTF-8 sequence starting at s[i] (1 to 4), or 0 when it is invalid
/// (RFC 3629: no overlong forms, no surrogates, nothing past U+10FFFF); cp receives the code
/// point.
std::size_t utf8Sequence(std::string_view s, std::size_t i, std::uint32_t& cp) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char b0 = byte(i);
    std::size_t n;
    std::uint32_t min;
    if (b0 < 0x80) {
        cp = b0;
        return 1;
    } else if ((b0 & 0xE0) == 0xC0) {
        n = 2, min = 0x80, cp = b0 & 0x1F;
    } else if ((b0 & 0xF0) == 0xE0) {
        n = 3, min = 0x800, cp = b0 & 0x0F;
    } else if ((b0 & 0xF8) == 0xF0) {
        n = 4, min = 0x10000, cp = b0 & 0x07;
    } else {
        return 0;
    }
    if (s.size() - i < n) return 0;
    for (std::size_t k = 1; k < n; ++k) {
        if ((byte(i + k) & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (byte(i + k) & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
    return n;
}

void appendHex(std::string& out, const char* prefix, unsigned v, int digits) {
    static const char kHex[] = "0123456789abcdef";
    out += prefix;
    for (int d = digits - 1; d >= 0; --d) out += kHex[(v >> (4 * d)) & 0xF];
}

/// Appends the printable form of the character at s[i] and returns its length in bytes.
std::size_t appendPrintable(std::string& out, std::string_view s, std::size_t i) {
    std::uint32_t cp = 0;
    const std::size_t n = utf8Sequence(s, i, cp);
    if (n == 0) {
        appendHex(out, "\\x", static_cast<unsigned char>(s[i]), 2);
        return 1;
    }
    if (cp == '\n') {
        out += "\\n";
    } else if (cp == '\r') {
        out += "\\r";
    } else if (cp == '\t') {
        out += "\\t";
    } else if (cp < 0x20 || cp == 0x7F) {
        appendHex(out, "\\x", cp, 2);
    } else if (cp >= 0x80 && cp <= 0x9F) {
        appendHex(out, "\\u", cp, 4);
    } else {
        out.append(s.substr(i, n));
    }
    return n;
}

}  // namespace

std::string printable(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size();) i += appendPrintable(out, text, i);
    return out;
}

std::string printableShort(std::string_view text, std::size_t maxBytes) {
    if (maxBytes < 4) maxBytes = 4;
    std::string out;
    std::size_t cut = 0;  // length of out at the last boundary that leaves room for "..."
    for (std::size_t i = 0; i < text.size();) {
        i += appendPrintable(out, text, i);
        if (out.size() <= maxBytes - 3) cut = out.size();
        if (out.size() > maxBytes) return out.substr(0, cut) + "...";
    }
    return out;
}

std::u32string decodeUtf8Lossy(std::string_view text) {
    std::u32string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size();) {
        std::uint32_t cp = 0;
        const std::size_t n = utf8Sequence(text, i, cp);
        out += n == 0 ? U'\uFFFD' : static_cast<char32_t>(cp);
        i += n == 0 ? 1 : n;
    }
    return out;
}

std::string encodeUtf8(std::u32string_view text) {
    std::string out;
    out.reserve(text.size());
    for (char32_t c : text) {
        std::uint32_t cp = c;
        if (cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) cp = 0xFFFD;
        if (cp < 0x80) {
            out += static_cast<char>(cp);
        } else if (cp < 0x800) {
            out += static_cast<char>(0xC0 | (cp >> 6));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else if (cp < 0x10000) {
            out += static_cast<char>(0xE0 | (cp >> 12));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        } else {
            out += static_cast<char>(0xF0 | (cp >> 18));
            out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
            out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (cp & 0x3F));
        }
    }
    return out;
}

bool isValidUtf8(std::string_view text) {
    std::uint32_t cp = 0;
    for (std::size_t i = 0; i < text.size();) {
        const std::size_t n = utf8Sequence(text, i, cp);
        if (n == 0) return false;
        i += n;
    }
    return true;
}

const char* wideTextEncoding(const void* data, std::size_t size) {
    const auto* b = static_cast<const unsigned char*>(data);
    if (size >= 4 && ((b[0] == 0 && b[1] == 0 && b[2] == 0xFE && b[3] == 0xFF) ||
                      (b[0] == 0xFF && b[1] == 0xFE && b[2] == 0 && b[3] == 0)))
        return "UTF-32";
    if (size >= 2 && ((b[0] == 0xFE && b[1] == 0xFF) || (b[0] == 0xFF && b[1] == 0xFE)))
        return "UTF-16";
    if (size < 4) return nullptr;
    // No byte-order mark: an ASCII character (such as '<', '{' or a space) with NUL bytes.
    const bool z0 = b[0] == 0, z1 = b[1] == 0, z2 = b[2] == 0, z3 = b[3] == 0;
    if ((!z0 && z1 && z2 && z3) || (z0 && z1 && z2 && !z3)) return "UTF-32";
    if ((!z0 && z1 && !z2 && z3) || (z0 && !z1 && z2 && !z3)) return "UTF-16";
    return nullptr;
}

std::size_t jsonTooDeepAt(std::string_view text, int maxDepth) {
    int depth = 0;
    bool inString = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > maxDepth) return i;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return std::string_view::npos;
}

int editDistance(std::string_view a, std::string_view b) {
    std::vector<int> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = static_cast<int>(j);
    for (std::size_t i = 1; i <= a.size(); ++i) {
        int diagonal = row[0];
        row[0] = static_cast<int>(i);
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const int up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
            diagonal = up;
        }
    }
    return row[b.size()];
}

std::vector<std::string> closeMatches(const std::string& word,
                                      const std::vector<std::string>& candidates,
                                      std::size_t maxCount) {
    const int limit = std::max(2, static_cast<int>(word.size()) / 3);
    std::vector<std::pair<int, std::string>> scored;
    for (const std::string& c : candidates) {
        int d = editDistance(word, c);
        const bool contains =
            word.size() >= 3 && c.size() >= 3 &&
            (c.find(word) != std::string::npos || word.find(c) != std::string::npos);
        if (contains) d = std::min(d, limit);
        if (d <= limit) scored.emplace_back(d, c);
    }
    std::stable_sort(scored.begin(), scored.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<std::string> out;
    for (const auto& s : scored) {
        if (out.size() >= maxCount) break;
        if (std::find(out.begin(), out.end(), s.second) == out.end()) out.push_back(s.second);
    }
    return out;
}

std::string formatG(double value, int significant) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", significant, value);
    return buf;
}

std::string formatExact(double value) {
    char buf[40];
    const std::to_chars_result r = std::to_chars(buf, buf + sizeof buf, value);
    return std::string(buf, r.ptr);
}

}  // namespace uvr

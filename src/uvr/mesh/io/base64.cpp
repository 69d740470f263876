// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/base64.h"

#include <algorithm>
#include <cstdio>

#include "uvr/core/error.h"

namespace uvr {

namespace {

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int sextet(unsigned char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

bool isSpace(unsigned char c) {
    return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\f' || c == '\v';
}

std::string describe(unsigned char c) {
    if (c >= 0x21 && c < 0x7f) return std::string("'") + static_cast<char>(c) + "'";
    char buf[8];
    std::snprintf(buf, sizeof(buf), "0x%02x", c);
    return buf;
}

}  // namespace

Base64Reader::Base64Reader(std::string_view text, Base64Origin origin)
    : text_(text), origin_(std::move(origin)) {}

bool Base64Reader::decodeGroup() {
    int values[4];
    int count = 0, padding = 0;
    std::uint64_t groupStart = 0;
    while (count < 4) {
        while (pos_ < text_.size() && isSpace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
        if (pos_ >= text_.size()) {
            if (count == 0) return false;
            throwParseError(origin_.file, atByte(origin_.byteOffset + groupStart),
                            (origin_.context.empty() ? "" : origin_.context + ": ") +
                                "base64 text ends inside a 4-character group (" +
                                std::to_string(count) + " of 4 characters)");
        }
        if (count == 0) groupStart = pos_;
        const unsigned char c = static_cast<unsigned char>(text_[pos_]);
        if (c == '=' && count >= 2) {
            ++padding;
            values[count++] = 0;
        } else {
            const int v = sextet(c);
            if (v < 0 || padding > 0)
                throwParseError(origin_.file, atByte(origin_.byteOffset + pos_),
                                (origin_.context.empty() ? "" : origin_.context + ": ") +
                                    "expected a base64 character (A-Z a-z 0-9 + / or '=' "
                                    "padding), got " +
                                    describe(c));
            values[count++] = v;
        }
        ++pos_;
    }
    const std::uint32_t bits = (static_cast<std::uint32_t>(values[0]) << 18) |
                               (static_cast<std::uint32_t>(values[1]) << 12) |
                               (static_cast<std::uint32_t>(values[2]) << 6) |
                               static_cast<std::uint32_t>(values[3]);
    pending_[0] = static_cast<unsigned char>(bits >> 16);
    pending_[1] = static_cast<unsigned char>(bits >> 8);
    pending_[2] = static_cast<unsigned char>(bits);
    pendingBegin_ = 0;
    pendingEnd_ = 3 - padding;
    return true;
}

void Base64Reader::read(std::size_t n, std::vector<unsigned char>& out) {
    if (out.capacity() < out.size() + n) out.reserve(std::max(out.size() + n, 2 * out.capacity()));
    while (n > 0) {
        if (pendingBegin_ == pendingEnd_ && !decodeGroup())
            throwParseError(origin_.file, atByte(fileOffset()),
                            (origin_.context.empty() ? "" : origin_.context + ": ") +
                                "base64 data ends early: expected " + std::to_string(n) +
                                " more byte(s)");
        while (n > 0 && pendingBegin_ < pendingEnd_) {
            out.push_back(pending_[pendingBegin_++]);
            --n;
        }
    }
}

std::uint64_t Base64Reader::remainingBound() const {
    return static_cast<std::uint64_t>(pendingEnd_ - pendingBegin_) + (text_.size() - pos_) / 4 * 3 +
           3;
}

bool Base64Reader::atEnd() {
    if (pendingBegin_ < pendingEnd_) return false;
    while (pos_ < text_.size() && isSpace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return pos_ >= text_.size();
}

std::vector<unsigned char> decodeBase64(std::string_view text, const Base64Origin& origin) {
    Base64Reader reader(text, origin);
    std::vector<unsigned char> out;
    out.reserve(text.size() / 4 * 3);
    while (!reader.atEnd()) reader.read(1, out);
    return out;
}

std::string encodeBase64(const unsigned char* data, std::size_t size) {
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    for (std::size_t i = 0; i < size; i += 3) {
        const std::size_t n = size - i < 3 ? size - i : 3;
        std::uint32_t bits = static_cast<std::uint32_t>(data[i]) << 16;
        if (n > 1) bits |= static_cast<std::uint32_t>(data[i + 1]) << 8;
        if (n > 2) bits |= data[i + 2];
        out += kAlphabet[(bits >> 18) & 63];
        out += kAlphabet[(bits >> 12) & 63];
        out += n > 1 ? kAlphabet[(bits >> 6) & 63] : '=';
        out += n > 2 ? kAlphabet[bits & 63] : '=';
    }
    return out;
}

}  // namespace uvr

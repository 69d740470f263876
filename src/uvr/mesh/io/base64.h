// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace uvr {

/// Where base64 text comes from, for error messages: file, file byte offset of text[0], context.
struct Base64Origin {
    std::string file;              ///< file named in errors
    std::uint64_t byteOffset = 0;  ///< file byte offset of the first character of the text
    std::string context;           ///< e.g. "Piece 0: DataArray 'offsets'" (may be empty)
};

/// Streaming base64 (RFC 4648) decoder over 4-character groups that skips whitespace and lets a
/// '='-padded group end early and decoding continue after it, so both one joined run and the
/// separate header/data runs VTK writes decode to the concatenated bytes.
class Base64Reader {
public:
    /// Decodes text (which must outlive the reader); errors name origin.file and the file byte
    /// offset of the offending character.
    Base64Reader(std::string_view text, Base64Origin origin);

    /// Appends exactly n decoded bytes to out; throws Error(Parse) when the text ends first.
    void read(std::size_t n, std::vector<unsigned char>& out);
    /// Upper bound on the bytes still decodable from the remaining text.
    std::uint64_t remainingBound() const;
    /// True when only whitespace remains and no decoded byte is pending.
    bool atEnd();
    /// File byte offset of the next undecoded character.
    std::uint64_t fileOffset() const { return origin_.byteOffset + pos_; }

private:
    bool decodeGroup();  // decodes the next group into pending_; false at end of text

    std::string_view text_;
    Base64Origin origin_;
    std::size_t pos_ = 0;
    unsigned char pending_[3] = {};
    int pendingBegin_ = 0, pendingEnd_ = 0;
};

/// Decodes all of text (see Base64Reader); throws Error(Parse) naming the bad character's offset.
std::vector<unsigned char> decodeBase64(std::string_view text, const Base64Origin& origin = {});

/// Encodes bytes as one padded base64 run (used by tests and writers).
std::string encodeBase64(const unsigned char* data, std::size_t size);

}  // namespace uvr

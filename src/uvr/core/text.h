// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace uvr {

/// Text from a file (a field or file name, a quoted token) made safe for a one-line message or
/// output line: valid UTF-8 is kept, control characters become \n, \r, \t or \xNN (C1 controls
/// \u0080 .. \u009F), and every byte of invalid UTF-8 becomes \xNN. For display only: a
/// backslash already in the text is kept as it is, so the escaping is not reversible.
std::string printable(std::string_view text);

/// printable(text) when it is at most maxBytes long, else cut on a character (or escape) boundary
/// with "..." appended to at most maxBytes (maxBytes >= 4).
std::string printableShort(std::string_view text, std::size_t maxBytes = 40);

/// The code points of a UTF-8 text for drawing it: valid sequences decode as they are, and every
/// byte of invalid UTF-8 becomes U+FFFD (the replacement character), so any bytes decode.
std::u32string decodeUtf8Lossy(std::string_view text);

/// The UTF-8 encoding of code points (one outside U+0000..U+10FFFF or a surrogate becomes
/// U+FFFD): decodeUtf8Lossy's inverse for valid text.
std::string encodeUtf8(std::u32string_view text);

/// True when text is well-formed UTF-8 (no overlong forms, surrogates or code points past
/// U+10FFFF).
bool isValidUtf8(std::string_view text);

/// A number for a message: printf's "%.Ng" with `significant` digits ("0.0173", "1.72e+12").
std::string formatG(double value, int significant);

/// The shortest text that reads back as exactly `value` ("0.1", not "0.10000000000000001"): for
/// numbers written to files (a .pvd's times) and reports.
std::string formatExact(double value);

/// "UTF-32" or "UTF-16" when the start of a text file is in one of those encodings (a byte-order
/// mark, or NUL bytes among the first four, which UTF-8 text never has), else nullptr. Readers of
/// UTF-8 formats use it to refuse such files with a clear message.
const char* wideTextEncoding(const void* data, std::size_t size);

/// Deepest nesting of JSON arrays and objects that uvr parses (a ParaView colour map nests 3
/// levels, a viewer message 4): deeper text is refused before a parser sees it.
inline constexpr int kMaxJsonDepth = 64;

/// Byte offset of the first '[' or '{' of a JSON text that opens a level deeper than maxDepth
/// (brackets inside strings do not count), or std::string_view::npos when none does. A linear
/// scan without recursion, run before parsing so that neither the parser nor a later copy or
/// dump of the value recurses deeper than maxDepth.
std::size_t jsonTooDeepAt(std::string_view text, int maxDepth = kMaxJsonDepth);

/// Edit distance (insertions, deletions, substitutions of bytes) between two words.
int editDistance(std::string_view a, std::string_view b);

/// Up to maxCount of the candidates close to `word`: within a third of its length in edits (at
/// least 2), or containing it, or contained in it (3 bytes or more), closest first; for "did you
/// mean" lists of names.
std::vector<std::string> closeMatches(const std::string& word,
                                      const std::vector<std::string>& candidates,
                                      std::size_t maxCount = 5);

}  // namespace uvr

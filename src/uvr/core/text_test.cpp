// SPDX-License-Identifier: MIT
#include "uvr/core/text.h"

#include <gtest/gtest.h>

#include <string>

namespace uvr {
namespace {

using namespace std::string_literals;

TEST(Text, PrintableKeepsValidUtf8AndEscapesControlsAndBadBytes) {
    EXPECT_EQ(printable("density"), "density");
    EXPECT_EQ(printable("Temperatur \xC2\xB0"
                        "C \xE2\x86\x92 \xF0\x9F\x94\xA5"),
              "Temperatur \xC2\xB0"
              "C \xE2\x86\x92 \xF0\x9F\x94\xA5");
    EXPECT_EQ(printable("a\nb\rc\td"), "a\\nb\\rc\\td");
    EXPECT_EQ(printable("nul\0esc\x1b del\x7f"s), "nul\\x00esc\\x1b del\\x7f");
    EXPECT_EQ(printable("c1 \xC2\x85"), "c1 \\u0085");
    // Invalid UTF-8: a lone continuation byte, a truncated sequence, an overlong '/', a UTF-16
    // surrogate, a code point past U+10FFFF and bytes no UTF-8 has.
    EXPECT_EQ(printable("\x80x"), "\\x80x");
    EXPECT_EQ(printable("\xE2\x86"), "\\xe2\\x86");
    EXPECT_EQ(printable("\xC0\xAF"), "\\xc0\\xaf");
    EXPECT_EQ(printable("\xED\xA0\x80"), "\\xed\\xa0\\x80");
    EXPECT_EQ(printable("\xF4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");
    EXPECT_EQ(printable("\xFF\xFE"), "\\xff\\xfe");
    EXPECT_EQ(printable("\xFF\n").find('\n'), std::string::npos);
}

TEST(Text, PrintableShortCutsOnACharacterBoundary) {
    EXPECT_EQ(printableShort("short"), "short");
    EXPECT_EQ(printableShort(std::string(40, 'a')), std::string(40, 'a'));
    std::string dots(40, '.');  // 37 a's and "..." (not a + "...": GCC 12's -Warray-bounds)
    dots.replace(0, 37, std::string(37, 'a'));
    EXPECT_EQ(printableShort(std::string(41, 'a')), dots);
    EXPECT_EQ(printableShort(std::string(1000000, '\n'), 10), "\\n\\n\\n...");
    // A two-byte character is not cut in half.
    std::string accents;
    for (int i = 0; i < 30; ++i) accents += "\xC3\xA9";
    const std::string cut = printableShort(accents, 12);
    EXPECT_EQ(cut, "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9...");
    EXPECT_LE(cut.size(), 12u);
}

TEST(Text, JsonTooDeepAtFindsTheFirstBracketPastTheLimit) {
    EXPECT_EQ(jsonTooDeepAt(R"({"a": [[1], {"b": 2}]})", 3), std::string_view::npos);
    EXPECT_EQ(jsonTooDeepAt(R"({"a": [[1], {"b": 2}]})", 2), 7u);
    EXPECT_EQ(jsonTooDeepAt(R"(["[[[[", "\"[[[["])", 1), std::string_view::npos);  // in strings
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    EXPECT_EQ(jsonTooDeepAt(deep), std::size_t(kMaxJsonDepth));
    EXPECT_EQ(jsonTooDeepAt(deep, 100000), std::string_view::npos);
}

TEST(Text, IsValidUtf8) {
    EXPECT_TRUE(isValidUtf8(""));
    EXPECT_TRUE(isValidUtf8("plain \xE2\x82\xAC"));
    EXPECT_FALSE(isValidUtf8("\xE2\x82"));
    EXPECT_FALSE(isValidUtf8("\xC1\xBF"));
    EXPECT_FALSE(isValidUtf8("bad \xFF name"));
}

TEST(Text, DecodeUtf8LossyReplacesEachBadByte) {
    EXPECT_EQ(decodeUtf8Lossy(""), U"");
    EXPECT_EQ(decodeUtf8Lossy("a\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80"), U"a\u00E9\u20AC\U0001F600");
    EXPECT_EQ(decodeUtf8Lossy("x\xFFy"), U"x\uFFFDy");
    EXPECT_EQ(decodeUtf8Lossy("\xE2\x82"), U"\uFFFD\uFFFD");  // truncated: each byte replaced
    EXPECT_EQ(decodeUtf8Lossy("\xC1\xBF"), U"\uFFFD\uFFFD");  // overlong
    EXPECT_EQ(decodeUtf8Lossy("\xED\xA0\x80"), U"\uFFFD\uFFFD\uFFFD");  // a surrogate
}

TEST(Text, EncodeUtf8InvertsDecodingAndReplacesNonCharacters) {
    const std::string text = "a\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80";
    EXPECT_EQ(encodeUtf8(decodeUtf8Lossy(text)), text);
    EXPECT_EQ(encodeUtf8(decodeUtf8Lossy("x\xFF")), "x\xEF\xBF\xBD");
    EXPECT_EQ(encodeUtf8(std::u32string(1, char32_t(0xD800))), "\xEF\xBF\xBD");
    EXPECT_EQ(encodeUtf8(std::u32string(1, char32_t(0x110000))), "\xEF\xBF\xBD");
}

TEST(Text, WideTextEncodingSeesByteOrderMarksAndNulPatterns) {
    const auto enc = [](const std::string& s) {
        const char* e = wideTextEncoding(s.data(), s.size());
        return std::string(e ? e : "");
    };
    EXPECT_EQ(enc("<?xml version"), "");
    EXPECT_EQ(enc("\xEF\xBB\xBF<?xml"), "");  // a UTF-8 byte-order mark is UTF-8
    EXPECT_EQ(enc(""), "");
    EXPECT_EQ(enc("\xFF\xFE<\0?\0"s), "UTF-16");
    EXPECT_EQ(enc("\xFE\xFF\0<\0?"s), "UTF-16");
    EXPECT_EQ(enc("<\0?\0x\0"s), "UTF-16");
    EXPECT_EQ(enc("\0[\0{"s), "UTF-16");
    EXPECT_EQ(enc("\xFF\xFE\0\0<\0\0\0"s), "UTF-32");
    EXPECT_EQ(enc("\0\0\xFE\xFF"s), "UTF-32");
    EXPECT_EQ(enc("[\0\0\0"s), "UTF-32");
    EXPECT_EQ(enc("\0\0\0["s), "UTF-32");
}

}  // namespace
}  // namespace uvr

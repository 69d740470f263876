// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/base64.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;

std::string decodeToString(std::string_view text) {
    const std::vector<unsigned char> bytes = decodeBase64(text);
    return std::string(bytes.begin(), bytes.end());
}

std::string encodeString(const std::string& s) {
    return encodeBase64(reinterpret_cast<const unsigned char*>(s.data()), s.size());
}

TEST(Base64, DecodesRfc4648TestVectors) {
    EXPECT_EQ(decodeToString(""), "");
    EXPECT_EQ(decodeToString("Zg=="), "f");
    EXPECT_EQ(decodeToString("Zm8="), "fo");
    EXPECT_EQ(decodeToString("Zm9v"), "foo");
    EXPECT_EQ(decodeToString("Zm9vYg=="), "foob");
    EXPECT_EQ(decodeToString("Zm9vYmE="), "fooba");
    EXPECT_EQ(decodeToString("Zm9vYmFy"), "foobar");
}

TEST(Base64, EncodesRfc4648TestVectors) {
    EXPECT_EQ(encodeString("f"), "Zg==");
    EXPECT_EQ(encodeString("fo"), "Zm8=");
    EXPECT_EQ(encodeString("foobar"), "Zm9vYmFy");
}

TEST(Base64, RoundTripsEveryByteValue) {
    std::vector<unsigned char> bytes(256);
    for (int i = 0; i < 256; ++i) bytes[i] = static_cast<unsigned char>(255 - i);
    EXPECT_EQ(decodeBase64(encodeBase64(bytes.data(), bytes.size())), bytes);
}

TEST(Base64, SeparatePaddedRunsDecodeToTheConcatenation) {
    // VTK encodes a header and its data as two runs, each padded on its own.
    const std::string all = "0123456789abcdef";
    for (std::size_t a = 0; a <= 7; ++a) {
        for (std::size_t b = 0; b <= 7; ++b) {
            const std::string first = all.substr(0, a), second = all.substr(8, b);
            EXPECT_EQ(decodeToString(encodeString(first) + encodeString(second)), first + second)
                << "runs of " << a << " and " << b << " bytes";
        }
    }
}

TEST(Base64, SkipsWhitespaceBetweenCharacters) {
    EXPECT_EQ(decodeToString("\n  Zm9v\r\n Ym\tFy \n"), "foobar");
}

TEST(Base64, ReaderReadsExactCountsAcrossPaddedRuns) {
    const std::string text = encodeString("ab") + encodeString("cdefg");
    Base64Reader reader(text, {});
    std::vector<unsigned char> out;
    reader.read(1, out);
    reader.read(3, out);
    EXPECT_FALSE(reader.atEnd());
    reader.read(3, out);
    EXPECT_TRUE(reader.atEnd());
    EXPECT_EQ(std::string(out.begin(), out.end()), "abcdefg");
}

TEST(Base64, BadCharacterNamesFileOffsetAndContext) {
    const Error e = testing::catchError([] {
        decodeBase64("Zm9v\nY#Fy", {"mesh.vtu", 100, "Piece 0: DataArray 'x'"});
    });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("mesh.vtu: byte 106: Piece 0: DataArray 'x'"));
    EXPECT_THAT(e.what(), HasSubstr("got '#'"));
}

TEST(Base64, DataAfterPaddingInsideAGroupIsRefused) {
    const Error e = testing::catchError([] { decodeBase64("Zg=a", {"f.vtu", 0, ""}); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("f.vtu: byte 3:"));
}

TEST(Base64, TruncatedGroupIsRefused) {
    const Error e = testing::catchError([] { decodeBase64("Zm9vYm", {"f.vtu", 10, ""}); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("f.vtu: byte 14:"));
    EXPECT_THAT(e.what(), HasSubstr("2 of 4 characters"));
}

TEST(Base64, ReadingPastTheEndIsRefused) {
    const Error e = testing::catchError([] {
        Base64Reader reader("Zm9v", {"f.vtu", 0, "ctx"});
        std::vector<unsigned char> out;
        reader.read(5, out);
    });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr("expected 2 more byte(s)"));
}

}  // namespace
}  // namespace uvr

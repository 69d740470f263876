// SPDX-License-Identifier: MIT
#include "uvr/core/setting_error.h"

#include <gtest/gtest.h>

#include <string>

namespace uvr {
namespace {

std::string cliSpelling(std::string_view message) {
    return respellMentions(message, [](std::string_view name) {
        std::string flag = "--" + std::string(name);
        for (char& c : flag)
            if (c == '_') c = '-';
        return flag;
    });
}

TEST(SettingError, SpelledInEachFrontEndsWords) {
    const SettingError e("max_sample_distance", "0.1", "below `sample_distance` 0.2");
    EXPECT_EQ(e.kind(), ErrorKind::Argument);
    EXPECT_STREQ(e.what(), "max_sample_distance 0.1: below `sample_distance` 0.2");
    EXPECT_EQ(e.setting(), "max_sample_distance");
    EXPECT_EQ(e.spelledAs("--max-sample-distance", " "),
              "--max-sample-distance 0.1: below `sample_distance` 0.2");
    EXPECT_EQ(cliSpelling(e.spelledAs("--max-sample-distance", " ")),
              "--max-sample-distance 0.1: below --sample-distance 0.2");
    EXPECT_EQ(e.spelledAs("max_sample_distance", "="),
              "max_sample_distance=0.1: below `sample_distance` 0.2");
    EXPECT_EQ(SettingError("device", "cuda", "none", ErrorKind::Unsupported).kind(),
              ErrorKind::Unsupported);
}

TEST(SettingError, OnlyMentionsOfNamesAreRespelled) {
    EXPECT_EQ(cliSpelling("narrow it with `range` LO,HI"), "narrow it with --range LO,HI");
    EXPECT_EQ(cliSpelling("`log` over `range`"), "--log over --range");
    EXPECT_EQ(cliSpelling("`opacity_unit``sample_distance`"), "--opacity-unit--sample-distance");
    // Commands, file names and stray backticks are text, not mentions.
    EXPECT_EQ(cliSpelling("(`uvr presets` lists them)"), "(`uvr presets` lists them)");
    EXPECT_EQ(cliSpelling("`Temp` and `a.vtk`"), "`Temp` and `a.vtk`");
    EXPECT_EQ(cliSpelling("a ` alone, `` empty, `open"), "a ` alone, `` empty, `open");
    EXPECT_EQ(cliSpelling("`sample_distance` then `"), "--sample-distance then `");
    EXPECT_EQ(cliSpelling(""), "");
    // A front end that does not know a name gives the mention back.
    EXPECT_EQ(respellMentions("use `power`",
                              [](std::string_view n) {
                                  return n == "sample_distance" ? std::string("--sample-distance")
                                                                : "`" + std::string(n) + "`";
                              }),
              "use `power`");
}

}  // namespace
}  // namespace uvr

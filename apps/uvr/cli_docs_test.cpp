// SPDX-License-Identifier: MIT
// The command lines the README and docs/ show must still parse: every `uvr COMMAND --flag` they
// name exists in that command's --help, so the docs cannot rot silently (issue 15).
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "cli_test_support.h"
#include "test_support.h"
#include "uvr/render/settings_vocabulary.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::uvr;

std::filesystem::path repoRoot() {
    return std::filesystem::path(UVR_TEST_TOOLS_DIR).parent_path().parent_path();
}

/// Every flag (--name) of a command's help text, and of the global help.
class HelpIndex {
public:
    explicit HelpIndex(const std::string& dir) : dir_(dir) {}
    bool knows(const std::string& command, const std::string& flag) {
        return flags(command).count(flag) > 0 || flags("").count(flag) > 0;
    }
    bool commandExists(const std::string& command) { return !flags(command).empty(); }

private:
    const std::set<std::string>& flags(const std::string& command) {
        auto it = cache_.find(command);
        if (it != cache_.end()) return it->second;
        std::set<std::string>& out = cache_[command];
        const CliRun r = uvr((command.empty() ? "" : command + " ") + "--help", dir_);
        if (r.code != 0) return out;
        const std::regex flag("--[a-z][a-z0-9-]*");
        for (std::sregex_iterator m(r.out.begin(), r.out.end(), flag), end; m != end; ++m)
            out.insert(m->str());
        out.insert("--help");
        return out;
    }
    std::string dir_;
    std::map<std::string, std::set<std::string>> cache_;
};

TEST(CliDocs, EverySettingOfTheLibrarysVocabularyIsARenderFlagWithItsChoices) {
    const std::string dir = testing::scratchDir();
    const CliRun help = uvr("render --help", dir);
    ASSERT_EQ(help.code, 0);
    HelpIndex index(dir);
    for (const SettingDef& d : settingsVocabulary()) {
        EXPECT_TRUE(index.knows("render", cliFlag(d))) << d.name;
        if (d.type != SettingType::Choice) continue;
        // CLI11 lists a flag's choices as {a,b,c}: the vocabulary's, in its order.
        std::string choices;
        for (const std::string& c : d.choices) choices += (choices.empty() ? "" : ",") + c;
        EXPECT_NE(help.out.find(cliFlag(d) + " TEXT:{" + choices + "}"), std::string::npos)
            << d.name << ": " << choices;
    }
}

TEST(CliDocs, EveryCommandLineInTheReadmeAndDocsParses) {
    const std::string dir = testing::scratchDir();
    HelpIndex help(dir);
    std::vector<std::filesystem::path> files = {repoRoot() / "README.md"};
    for (const auto& e : std::filesystem::directory_iterator(repoRoot() / "docs"))
        if (e.path().extension() == ".md") files.push_back(e.path());
    // "uvr COMMAND ..." (or build/release/uvr ...) up to the end of its code span or line.
    const std::regex commandLine(
        R"((?:^|[\s`(/])uvr((?: -q| --quiet| --max-memory \S+)*) ([a-z]+)([^`\n]*))");
    const std::regex flag("(?:^|\\s)(--[a-z][a-z0-9-]*)");
    int lines = 0;
    for (const auto& file : files) {
        std::istringstream text(testing::readFile(file));
        std::string line;
        int number = 0;
        while (std::getline(text, line)) {
            ++number;
            for (std::sregex_iterator m(line.begin(), line.end(), commandLine), end; m != end;
                 ++m) {
                const std::string command = (*m)[2], rest = (*m)[3];
                const std::string where =
                    file.filename().string() + ":" + std::to_string(number) + ": " + line;
                // Prose such as "uvr renders" is not a command line.
                static const std::set<std::string> kCommands = {
                    "info",   "render",  "demo",  "convert", "generate",
                    "refine", "compare", "bench", "presets", "prepare"};
                if (!kCommands.count(command)) continue;
                ++lines;
                EXPECT_TRUE(help.commandExists(command)) << where;
                for (std::sregex_iterator f(rest.begin(), rest.end(), flag); f != end; ++f)
                    EXPECT_TRUE(help.knows(command, (*f)[1])) << (*f)[1] << " in " << where;
            }
        }
    }
    EXPECT_GT(lines, 20);  // the pattern finds the docs' command lines at all
}

TEST(CliDocs, EveryRenderOptionTheReadmeListsExists) {
    const std::string dir = testing::scratchDir();
    HelpIndex help(dir);
    std::istringstream text(testing::readFile(repoRoot() / "README.md"));
    std::string line;
    int rows = 0;
    const std::regex flag("--[a-z][a-z0-9-]*");
    while (std::getline(text, line)) {
        if (line.rfind("| `-", 0) != 0) continue;
        const std::string cell = line.substr(0, line.find(" | "));
        ++rows;
        for (std::sregex_iterator f(cell.begin(), cell.end(), flag), end; f != end; ++f)
            EXPECT_TRUE(help.knows("render", f->str())) << f->str() << " in README: " << line;
    }
    EXPECT_GT(rows, 20);
}

}  // namespace
}  // namespace uvr

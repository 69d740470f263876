// SPDX-License-Identifier: MIT
// Running the uvr command-line tool from tests: its exit status, standard output and error.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace uvr::cli_testing {

/// What one run of the tool gave.
struct CliRun {
    int code = -1;
    std::string out, err;
};

/// Runs `uvr ARGS` in the folder dir (relative paths resolve there), capturing standard output
/// and error in dir/stdout.txt and dir/stderr.txt; env is put before the command (e.g.
/// "OMP_NUM_THREADS=8 " or "ulimit -v 1000000; ").
inline CliRun uvr(const std::string& args, const std::string& dir, const std::string& env = "") {
    const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
    CliRun r;
    r.code = testing::runCommand("cd " + dir + " && " + env + testing::uvrBinary() + " " + args +
                                 " >" + out + " 2>" + err);
    auto slurp = [](const std::string& p) {
        std::ifstream in(p, std::ios::binary);
        std::stringstream ss;
        ss << in.rdbuf();
        return ss.str();
    };
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

/// Lines of a text (its newlines).
inline int lineCount(const std::string& s) {
    return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

/// Expects a refusal: exit code 2 and exactly one stderr line "uvr: error: ..." holding every
/// piece (`what` names the case in failure messages).
inline void expectOneLineError(const CliRun& r, const std::vector<std::string>& pieces,
                               const std::string& what = "") {
    EXPECT_EQ(r.code, 2) << what << "\n" << r.err;
    EXPECT_EQ(lineCount(r.err), 1) << what << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("uvr: error: ", 0), 0u) << what << "\n" << r.err;
    for (const std::string& p : pieces)
        EXPECT_NE(r.err.find(p), std::string::npos) << what << ": no '" << p << "' in " << r.err;
}

}  // namespace uvr::cli_testing

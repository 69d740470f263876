// SPDX-License-Identifier: MIT
// Running the uvr command-line tool from tests: its exit status, standard output and error.
#pragma once

#include <gtest/gtest.h>

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
    r.out = testing::readFile(out);
    r.err = testing::readFile(err);
    return r;
}

/// Five tetrahedra filling the unit cube, legacy VTK, with the given data sections appended
/// (CELL_DATA before POINT_DATA as VTK's legacy writer puts them).
inline std::string fiveTetCubeVtk(const std::string& data) {
    return "# vtk DataFile Version 3.0\nfive tetrahedra\nASCII\nDATASET UNSTRUCTURED_GRID\n"
           "POINTS 8 float\n0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1\n"
           "CELLS 5 25\n4 0 1 3 4\n4 1 2 3 6\n4 1 4 5 6\n4 3 4 6 7\n4 1 3 4 6\n"
           "CELL_TYPES 5\n10 10 10 10 10\n" +
           data;
}

/// Expects a refusal: exit code 2 and exactly one stderr line "uvr: error: ..." holding every
/// piece (`what` names the case in failure messages).
inline void expectOneLineError(const CliRun& r, const std::vector<std::string>& pieces,
                               const std::string& what = "") {
    EXPECT_EQ(r.code, 2) << what << "\n" << r.err;
    EXPECT_EQ(testing::lineCount(r.err), 1) << what << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("uvr: error: ", 0), 0u) << what << "\n" << r.err;
    for (const std::string& p : pieces)
        EXPECT_NE(r.err.find(p), std::string::npos) << what << ": no '" << p << "' in " << r.err;
}

}  // namespace uvr::cli_testing

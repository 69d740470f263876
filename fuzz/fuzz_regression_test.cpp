// SPDX-License-Identifier: MIT
// Replays every kept fuzzing input (tests/fuzz_regressions/<target>/) and every hand-made seed
// (fuzz/seeds/<target>/) through its fuzz target's body: each must load or fail with a clear
// uvr::Error (never an internal error, another exception, a crash or, in the asan preset, a
// sanitizer report).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_targets.h"

namespace uvr {
namespace {

/// Replays the files in folder/<target>/ for every target; returns how many it replayed.
int replayAll(const std::string& folder) {
    namespace fs = std::filesystem;
    int replayed = 0;
    for (const fuzz::FuzzTarget& target : fuzz::kFuzzTargets) {
        const fs::path dir = fs::path(folder) / target.name;
        if (!fs::is_directory(dir)) continue;
        for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
            if (!entry.is_regular_file()) continue;
            std::ifstream in(entry.path(), std::ios::binary);
            const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
            SCOPED_TRACE(entry.path().string());
            EXPECT_NO_THROW(
                target.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
            ++replayed;
        }
    }
    return replayed;
}

TEST(FuzzRegressions, KeptInputsFailCleanly) {
    EXPECT_GT(replayAll(UVR_FUZZ_REGRESSIONS_DIR), 0);
}

TEST(FuzzRegressions, HandMadeSeedsLoadOrFailCleanly) {
    EXPECT_GT(replayAll(UVR_FUZZ_SEEDS_DIR), 10);
}

}  // namespace
}  // namespace uvr

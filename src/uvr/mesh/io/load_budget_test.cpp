// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/load_budget.h"

#include <gtest/gtest.h>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

TEST(LoadBudget, ChargesUpToTheLimitAndNamesTheTotal) {
    LoadBudget budget(1000);
    budget.charge("f.vtu", "points", 50, 12);
    EXPECT_EQ(budget.used(), 600u);
    try {
        budget.charge("f.vtu", "Piece 1: DataArray 'p'", 101, 4);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Resource);
        EXPECT_EQ(std::string(e.what()),
                  "f.vtu: Piece 1: DataArray 'p' needs 404 bytes, which with the 600 bytes this "
                  "load holds so far exceed the memory limit of 1000 bytes (`max_memory`)");
    }
    budget.release(200);
    budget.charge("f.vtu", "again", 100, 4);
    EXPECT_EQ(budget.used(), 800u);
    EXPECT_EQ(budget.peak(), 800u);
    budget.resetTo(100);
    EXPECT_EQ(budget.used(), 100u);
    EXPECT_EQ(budget.peak(), 800u);
}

TEST(LoadBudget, OverflowingCountsAreRefusedAndNoLimitOnlyCounts) {
    LoadBudget budget(1 << 20);
    EXPECT_THROW(budget.charge("f", "x", ~0ull / 2, 16), Error);
    EXPECT_EQ(budget.used(), 0u);
    LoadBudget unlimited;
    unlimited.charge("f", "x", 1ull << 40, 1);
    unlimited.charge("f", "y", ~0ull / 2, 16);  // saturates, never wraps
    EXPECT_EQ(unlimited.used(), ~0ull);
}

TEST(LoadBudget, ReadFileChargedRefusesAFileAboveTheLimitWithoutReadingIt) {
    const std::string path =
        testing::writeFile(testing::scratchDir() + "/f.bin", std::string(300, 'x'));
    LoadBudget small(299);
    try {
        readFileCharged(path, small);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), path +
                                             ": the file needs 300 bytes, which exceed the "
                                             "memory limit of 299 bytes (`max_memory`)");
    }
    LoadBudget enough(300);
    EXPECT_EQ(readFileCharged(path, enough).size(), 300u);
    EXPECT_EQ(enough.used(), 300u);
}

}  // namespace
}  // namespace uvr

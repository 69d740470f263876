// SPDX-License-Identifier: MIT
// huge_pages.cpp: large allocations start on a huge page and the kernel backs them with huge
// pages where it can.
#include "huge_pages.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace uvr::cli {
namespace {

/// The kB of huge pages (smaps' AnonHugePages) of the mapping that holds `p`; -1 when none
/// holds it.
long hugeKbAt(const void* p) {
    std::ifstream smaps("/proc/self/smaps");
    const auto at = reinterpret_cast<std::uintptr_t>(p);
    bool inside = false;
    for (std::string line; std::getline(smaps, line);) {
        std::uintptr_t lo = 0, hi = 0;
        char dash = 0;
        std::istringstream head(line);
        if (head >> std::hex >> lo >> dash >> hi && dash == '-') {
            inside = lo <= at && at < hi;
            continue;
        }
        if (inside && line.rfind("AnonHugePages:", 0) == 0)
            return std::stol(line.substr(line.find(':') + 1));
    }
    return -1;
}

TEST(HugePages, LargeAllocationsStartOnAHugePageAndGetHugePages) {
    if (!kHugePagesBuilt) GTEST_SKIP() << "a sanitizer build: operator new is the sanitizer's";
    std::vector<char> large(kHugeAllocationBytes + 12345);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large.data()) % kHugePageBytes, 0u);
    auto* array = new std::uint32_t[kHugeAllocationBytes / 4];
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(array) % kHugePageBytes, 0u);
    delete[] array;
    const std::string thp = testing::readFile("/sys/kernel/mm/transparent_hugepage/enabled");
    if (thp.empty() || thp.find("[never]") != std::string::npos)
        GTEST_SKIP() << "this kernel gives no transparent huge pages";
    for (std::size_t i = 0; i < large.size(); i += 4096) large[i] = 1;
    EXPECT_GT(hugeKbAt(large.data()), 0) << "transparent_hugepage: " << thp;
}

}  // namespace
}  // namespace uvr::cli

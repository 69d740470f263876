// SPDX-License-Identifier: MIT
// Host memory detection against fake /proc and /sys trees: a VM whose MemTotal is still small,
// cgroup caps, missing and garbled files.
#include "uvr/core/host_memory.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <vector>

#include "test_support.h"

namespace uvr {
namespace {

constexpr std::uint64_t kGiB = 1ull << 30;

/// An empty fake root folder for one test.
std::string fakeRoot(const std::string& name) {
    const std::filesystem::path root =
        std::filesystem::path(testing::scratchDir()) / ("host_memory_" + name);
    std::filesystem::remove_all(root);
    std::filesystem::create_directories(root / "proc");
    std::filesystem::create_directories(root / "sys/devices/system/memory");
    std::filesystem::create_directories(root / "sys/fs/cgroup/memory");
    return root.string();
}

void write(const std::string& root, const std::string& file, const std::string& text) {
    testing::writeFile(root + "/" + file, text);
}

/// memory0 .. memory<n-1>, as sysfs lists them.
void addBlocks(const std::string& root, int n, const std::string& hexSize) {
    write(root, "sys/devices/system/memory/block_size_bytes", hexSize + "\n");
    for (int i = 0; i < n; ++i)
        std::filesystem::create_directories(root + "/sys/devices/system/memory/memory" +
                                            std::to_string(i));
    std::filesystem::create_directories(root + "/sys/devices/system/memory/power");  // not a block
}

TEST(HostMemory, MemTotalAlone) {
    const std::string root = fakeRoot("memtotal");
    write(root, "proc/meminfo", "MemTotal:       24684084 kB\nMemFree:  100 kB\n");
    const HostMemory m = detectHostMemory(root, 7);
    EXPECT_EQ(m.bytes, 24684084ull * 1024);
    EXPECT_EQ(m.source, "MemTotal of /proc/meminfo");
}

TEST(HostMemory, SmallMemTotalAndManyBlocksTakesTheBlocks) {
    // A Firecracker VM: 31 GiB in MemTotal so far, 1024 blocks of 128 MiB = 128 GiB present.
    const std::string root = fakeRoot("blocks");
    write(root, "proc/meminfo", "MemTotal:       32505856 kB\n");
    addBlocks(root, 1024, "8000000");
    const HostMemory m = detectHostMemory(root, 7);
    EXPECT_EQ(m.bytes, 128 * kGiB);
    EXPECT_NE(m.source.find("1024 memory blocks of 128 MiB"), std::string::npos) << m.source;
}

TEST(HostMemory, FewerBlocksThanMemTotalKeepsMemTotal) {
    const std::string root = fakeRoot("fewblocks");
    write(root, "proc/meminfo", "MemTotal:       33554432 kB\n");  // 32 GiB
    addBlocks(root, 8, "0x8000000");                               // 1 GiB
    EXPECT_EQ(detectHostMemory(root, 7).bytes, 32 * kGiB);
}

TEST(HostMemory, CgroupV2LimitCaps) {
    const std::string root = fakeRoot("cgroup2");
    write(root, "proc/meminfo", "MemTotal:       33554432 kB\n");
    addBlocks(root, 1024, "8000000");
    write(root, "sys/fs/cgroup/memory.max", std::to_string(16 * kGiB) + "\n");
    const HostMemory m = detectHostMemory(root, 7);
    EXPECT_EQ(m.bytes, 16 * kGiB);
    EXPECT_NE(m.source.find("cgroup limit /sys/fs/cgroup/memory.max (physical 128 GiB)"),
              std::string::npos)
        << m.source;
}

TEST(HostMemory, CgroupMaxOrHugeMeansNoLimit) {
    const std::string root = fakeRoot("nocap");
    write(root, "proc/meminfo", "MemTotal:       33554432 kB\n");
    write(root, "sys/fs/cgroup/memory.max", "max\n");
    write(root, "sys/fs/cgroup/memory/memory.limit_in_bytes", "9223372036854771712\n");
    EXPECT_EQ(detectHostMemory(root, 7).bytes, 32 * kGiB);
}

TEST(HostMemory, CgroupV1LimitCaps) {
    const std::string root = fakeRoot("cgroup1");
    write(root, "proc/meminfo", "MemTotal:       33554432 kB\n");
    write(root, "sys/fs/cgroup/memory/memory.limit_in_bytes", std::to_string(4 * kGiB));
    EXPECT_EQ(detectHostMemory(root, 7).bytes, 4 * kGiB);
}

TEST(HostMemory, NothingReadableFallsBack) {
    const std::string root = fakeRoot("missing");
    const HostMemory m = detectHostMemory(root, 5 * kGiB);
    EXPECT_EQ(m.bytes, 5 * kGiB);
    EXPECT_EQ(m.source, "sysconf(_SC_PHYS_PAGES)");
    EXPECT_EQ(detectHostMemory(root + "/no/such/folder", 0).bytes, 0u);
}

TEST(HostMemory, GarbageIsIgnored) {
    const std::string root = fakeRoot("garbage");
    write(root, "proc/meminfo", "MemTotal:       lots kB\n");
    addBlocks(root, 4, "zz");  // not hexadecimal
    write(root, "sys/fs/cgroup/memory.max", "-5\n");
    write(root, "sys/fs/cgroup/memory/memory.limit_in_bytes", "0\n");
    EXPECT_EQ(detectHostMemory(root, 3 * kGiB).bytes, 3 * kGiB);
    // A block size that is no power of two, and MemTotal in another unit.
    write(root, "sys/devices/system/memory/block_size_bytes", "8000001\n");
    write(root, "proc/meminfo", "MemTotal:       33554432 MB\n");
    EXPECT_EQ(detectHostMemory(root, 3 * kGiB).bytes, 3 * kGiB);
    // A good MemTotal beside garbled blocks is kept.
    write(root, "proc/meminfo", "MemTotal:       33554432 kB\n");
    EXPECT_EQ(detectHostMemory(root, 3 * kGiB).bytes, 32 * kGiB);
}

TEST(HostMemory, PeakResidentBytesCountTouchedMemory) {
    // 256 MiB written page by page is resident at once: the peak is at least that.
    std::vector<char> block(std::size_t(256) << 20);
    std::memset(block.data(), 1, block.size());
    volatile char keep = block[block.size() / 2];
    (void)keep;
    EXPECT_GE(peakResidentBytes(), std::uint64_t(256) << 20);
}

}  // namespace
}  // namespace uvr

// SPDX-License-Identifier: MIT
#include "uvr/core/host_memory.h"

#include <sys/resource.h>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

namespace uvr {

namespace {

namespace fs = std::filesystem;

/// Sizes above this are not a machine's memory (garbage, or cgroup v1's "no limit").
constexpr std::uint64_t kIncredible = 1ull << 60;

/// The first line of a small text file, empty when it cannot be read.
std::string firstLine(const fs::path& path) {
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) return {};
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' '))
        line.pop_back();
    return line;
}

/// The whole of `text` as an unsigned number in `base`, or nothing.
std::optional<std::uint64_t> parseNumber(std::string_view text, int base) {
    if (base == 16 && (text.starts_with("0x") || text.starts_with("0X"))) text.remove_prefix(2);
    std::uint64_t value = 0;
    const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value, base);
    if (ec != std::errc() || ptr != text.data() + text.size() || text.empty()) return {};
    return value;
}

/// MemTotal of proc/meminfo in bytes, or nothing.
std::optional<std::uint64_t> memTotal(const fs::path& root) {
    std::ifstream in(root / "proc/meminfo");
    std::string line;
    while (in && std::getline(in, line)) {
        if (!line.starts_with("MemTotal:")) continue;
        std::istringstream fields(line.substr(9));
        std::string number, unit;
        fields >> number >> unit;
        const auto kib = parseNumber(number, 10);
        if (!kib || unit != "kB" || *kib == 0 || *kib >= kIncredible / 1024) return {};
        return *kib * 1024;
    }
    return {};
}

/// Memory blocks: block size times the memory<N> folders, or nothing.
std::optional<std::uint64_t> memoryBlocks(const fs::path& root, std::uint64_t& blockBytes,
                                          std::uint64_t& blocks) {
    const fs::path dir = root / "sys/devices/system/memory";
    const auto size = parseNumber(firstLine(dir / "block_size_bytes"), 16);
    // A block is a power of two of at least 1 MiB (x86-64: 128 MiB to 2 GiB).
    if (!size || *size < (1ull << 20) || *size > (1ull << 40) || (*size & (*size - 1)) != 0)
        return {};
    std::error_code ec;
    std::uint64_t count = 0;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() > 6 && name.starts_with("memory") && parseNumber(name.substr(6), 10))
            ++count;
    }
    if (ec || count == 0 || count > kIncredible / *size) return {};
    blockBytes = *size;
    blocks = count;
    return count * *size;
}

/// A cgroup memory limit in bytes, or nothing when none is set or it cannot be read.
std::optional<std::uint64_t> cgroupLimit(const fs::path& file) {
    const auto limit = parseNumber(firstLine(file), 10);
    if (!limit || *limit == 0 || *limit >= kIncredible) return {};
    return limit;
}

std::string gib(std::uint64_t bytes) {
    std::ostringstream s;
    s.precision(bytes >= (10ull << 30) ? 0 : 1);
    s << std::fixed << double(bytes) / double(1ull << 30) << " GiB";
    return s.str();
}

}  // namespace

HostMemory detectHostMemory(const std::string& root, std::uint64_t fallbackBytes) {
    const fs::path base(root);
    HostMemory m;
    // Physical size: the larger credible one of MemTotal and the memory blocks.
    if (const auto total = memTotal(base)) {
        m.bytes = *total;
        m.source = "MemTotal of /proc/meminfo";
    }
    std::uint64_t blockBytes = 0, blocks = 0;
    if (const auto b = memoryBlocks(base, blockBytes, blocks); b && *b > m.bytes) {
        m.bytes = *b;
        m.source = std::to_string(blocks) + " memory blocks of " +
                   std::to_string(blockBytes >> 20) + " MiB in /sys/devices/system/memory";
    }
    if (m.bytes == 0 && fallbackBytes > 0) {
        m.bytes = fallbackBytes;
        m.source = "sysconf(_SC_PHYS_PAGES)";
    }
    // A cgroup limit below it caps it.
    for (const char* file :
         {"sys/fs/cgroup/memory.max", "sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        const auto limit = cgroupLimit(base / file);
        if (limit && (m.bytes == 0 || *limit < m.bytes)) {
            m.source = "cgroup limit /" + std::string(file) +
                       (m.bytes ? " (physical " + gib(m.bytes) + ")" : "");
            m.bytes = *limit;
        }
    }
    return m;
}

std::uint64_t peakResidentBytes() {
    rusage usage{};
    if (getrusage(RUSAGE_SELF, &usage) != 0 || usage.ru_maxrss < 0) return 0;
    return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // Linux counts kilobytes
}

}  // namespace uvr

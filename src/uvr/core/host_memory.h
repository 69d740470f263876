// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>

namespace uvr {

/// The memory this process may use, and where that number was found.
struct HostMemory {
    std::uint64_t bytes = 0;  ///< 0 when nothing credible was found
    std::string source;       ///< e.g. "MemTotal of /proc/meminfo", for messages
};

/// The host's physical memory as read under `root` ("/" on a live system; a scratch folder with a
/// fake proc/ and sys/ in tests): the larger of MemTotal in proc/meminfo and the hot-pluggable
/// memory blocks in sys/devices/system/memory (block_size_bytes, hexadecimal, times the memory*
/// folders present, online or offline: a VM whose MemTotal grows as memory is touched lists its
/// whole memory there from the start), capped by a cgroup limit when one is set (v2
/// sys/fs/cgroup/memory.max, v1 sys/fs/cgroup/memory/memory.limit_in_bytes; "max" or 2^60 and
/// above mean none). Missing or garbled files are ignored; `fallbackBytes` (e.g. from sysconf)
/// is used when neither MemTotal nor the blocks can be read.
HostMemory detectHostMemory(const std::string& root, std::uint64_t fallbackBytes);

/// The most host memory this process has held resident so far (getrusage's maximum resident
/// set size), in bytes; 0 where the system does not say.
std::uint64_t peakResidentBytes();

}  // namespace uvr

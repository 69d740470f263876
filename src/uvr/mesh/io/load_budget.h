// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// The bytes one mesh load may hold at once, over all its arrays, pieces and file buffers:
/// readers charge each allocation before making it and release what they free, so a load that
/// would need more than the limit fails before allocating, however its file is built (blocks
/// reused by many arrays, one piece listed many times).
class LoadBudget {
public:
    /// A budget of limitBytes; 0 means no limit (allocations are only counted).
    explicit LoadBudget(std::uint64_t limitBytes = 0) : limit_(limitBytes) {}

    /// Charges count * elementSize bytes for `what` of `file`; throws Error(Resource) "FILE: WHAT
    /// needs N bytes, which with the M bytes this load holds so far exceed the memory limit of L
    /// bytes (--max-memory)" instead when they do not fit.
    void charge(const std::string& file, const std::string& what, std::uint64_t count,
                std::uint64_t elementSize);
    /// Throws what charge would throw for count * elementSize bytes more, charging nothing: for
    /// a need known before the allocations that make it up are charged one by one (the mesh a
    /// file declares, checked before decoding any of it).
    void check(const std::string& file, const std::string& what, std::uint64_t count,
               std::uint64_t elementSize) const;
    /// Returns bytes charged earlier for a buffer that has been freed.
    void release(std::uint64_t bytes) { used_ -= bytes < used_ ? bytes : used_; }
    /// Sets the bytes held, after a step whose temporaries are freed, to what it keeps.
    void resetTo(std::uint64_t bytes) { used_ = bytes; }

    /// The limit in bytes (0 = none).
    std::uint64_t limit() const { return limit_; }
    /// Bytes charged and not released.
    std::uint64_t used() const { return used_; }
    /// The most bytes charged at once.
    std::uint64_t peak() const { return peak_; }

private:
    std::uint64_t limit_ = 0;
    std::uint64_t used_ = 0;
    std::uint64_t peak_ = 0;
};

/// Reads a whole regular file into memory after charging its size to the budget (checked before
/// reading, so a huge or sparse file is refused without being read); the buffer stays charged
/// until the caller releases bytes.size(). Throws Error(Io) like readFileBytes.
std::vector<char> readFileCharged(const std::string& path, LoadBudget& budget);

/// Bytes of a mesh's arrays (points, cells, field values), as readers charge them.
std::uint64_t meshBytes(const Mesh& mesh);

}  // namespace uvr

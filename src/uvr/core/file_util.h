// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uvr {

/// Reads a whole file into memory; throws Error(Io) naming the file on failure, and
/// Error(Resource) "WHAT of N bytes exceeds the limit of M bytes" before reading when maxBytes is
/// non-zero and the file is larger.
std::vector<char> readFileBytes(const std::string& path, std::uint64_t maxBytes = 0,
                                const std::string& what = "file");

/// Throws Error(Io) when path names a folder, device, pipe or socket (checked before opening: a
/// pipe would block and a device has no size); a missing file is left to the caller's open.
void checkRegularFile(const std::string& path);

/// "uid N (name)" for messages naming a file's owner (the name where the system knows it).
std::string describeUser(std::uint32_t uid);

/// What a file of stat mode `mode` is, for messages: "a folder", "a FIFO", "a character device",
/// "a block device", "a socket", else "not a regular file".
const char* describeFileType(std::uint32_t mode);

/// Size of a file in bytes; throws Error(Io) when it cannot be opened.
std::uint64_t fileSize(const std::string& path);

/// Lower-cased extension of a path including the dot (".vtu"), or "" if none.
std::string fileExtension(const std::string& path);

/// Folder part of a path ("" for a bare file name).
std::string parentFolder(const std::string& path);

/// Refuses an allocation of count * elementSize bytes above limitBytes (0 = no limit) with
/// Error(Resource) naming the file and what was being allocated.
void checkAllocation(const std::string& file, const std::string& what, std::uint64_t count,
                     std::uint64_t elementSize, std::uint64_t limitBytes);

}  // namespace uvr

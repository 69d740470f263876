// SPDX-License-Identifier: MIT
#include "uvr/core/file_util.h"

#include <pwd.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "uvr/core/error.h"

namespace uvr {

std::vector<char> readFileBytes(const std::string& path, std::uint64_t maxBytes,
                                const std::string& what) {
    if (maxBytes) {
        const std::uint64_t size = fileSize(path);
        if (size > maxBytes)
            throwError(ErrorKind::Resource, path,
                       what + " of " + std::to_string(size) + " bytes exceeds the limit of " +
                           std::to_string(maxBytes) + " bytes");
    }
    checkRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throwError(ErrorKind::Io, path, std::string("cannot open: ") + std::strerror(errno));
    in.seekg(0, std::ios::end);
    std::streamoff size = in.tellg();
    if (size < 0) throwError(ErrorKind::Io, path, "cannot determine the file size");
    in.seekg(0, std::ios::beg);
    std::vector<char> bytes(static_cast<size_t>(size));
    if (size > 0 && !in.read(bytes.data(), size)) throwError(ErrorKind::Io, path, "read failed");
    return bytes;
}

void checkRegularFile(const std::string& path) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(status))
        throwError(ErrorKind::Io, path, "is a folder, not a file");
    if (!ec && !std::filesystem::is_regular_file(status))
        throwError(ErrorKind::Io, path, "is not a regular file (a device, pipe or socket)");
}

std::uint64_t fileSize(const std::string& path) {
    std::error_code ec;
    auto size = std::filesystem::file_size(path, ec);
    if (ec) throwError(ErrorKind::Io, path, "cannot open: " + ec.message());
    return size;
}

std::string fileExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

std::string parentFolder(const std::string& path) {
    return std::filesystem::path(path).parent_path().string();
}

void checkAllocation(const std::string& file, const std::string& what, std::uint64_t count,
                     std::uint64_t elementSize, std::uint64_t limitBytes) {
    if (limitBytes == 0) return;
    if (elementSize != 0 && count > limitBytes / elementSize) {
        throwError(ErrorKind::Resource, file,
                   what + ": " + std::to_string(count) + " entries of " +
                       std::to_string(elementSize) + " bytes exceed the memory limit of " +
                       std::to_string(limitBytes) + " bytes");
    }
}

std::string describeUser(std::uint32_t uid) {
    std::string out = "uid " + std::to_string(uid);
    struct passwd pw, *found = nullptr;
    char buf[1024];
    if (::getpwuid_r(static_cast<uid_t>(uid), &pw, buf, sizeof buf, &found) == 0 && found)
        out += std::string(" (") + found->pw_name + ")";
    return out;
}

const char* describeFileType(std::uint32_t mode) {
    const auto m = static_cast<mode_t>(mode);
    if (S_ISDIR(m)) return "a folder";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISSOCK(m)) return "a socket";
    return "not a regular file";
}

}  // namespace uvr

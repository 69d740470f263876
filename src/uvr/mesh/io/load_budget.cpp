// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/load_budget.h"

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"

namespace uvr {

namespace {

constexpr std::uint64_t kMax = ~std::uint64_t(0);

std::uint64_t bytesOf(std::uint64_t count, std::uint64_t elementSize) {
    return elementSize != 0 && count > kMax / elementSize ? kMax : count * elementSize;
}

}  // namespace

void LoadBudget::check(const std::string& file, const std::string& what, std::uint64_t count,
                       std::uint64_t elementSize) const {
    const std::uint64_t bytes = bytesOf(count, elementSize);
    if (limit_ != 0 && (bytes > limit_ || used_ > limit_ - bytes)) {
        const std::string need = bytes == kMax ? "more than 2^64" : std::to_string(bytes);
        throwError(
            ErrorKind::Resource, file,
            what + " needs " + need + " bytes, which " +
                (used_ ? "with the " + std::to_string(used_) + " bytes this load holds so far "
                       : std::string()) +
                "exceed the memory limit of " + std::to_string(limit_) + " bytes (`max_memory`)");
    }
}

void LoadBudget::charge(const std::string& file, const std::string& what, std::uint64_t count,
                        std::uint64_t elementSize) {
    check(file, what, count, elementSize);
    const std::uint64_t bytes = bytesOf(count, elementSize);
    used_ = used_ > kMax - bytes ? kMax : used_ + bytes;
    if (used_ > peak_) peak_ = used_;
}

std::vector<char> readFileCharged(const std::string& path, LoadBudget& budget) {
    checkRegularFile(path);
    budget.charge(path, "the file", fileSize(path), 1);
    return readFileBytes(path);
}

std::uint64_t meshBytes(const Mesh& mesh) {
    std::uint64_t bytes = mesh.points.size() * sizeof(Vec3f) +
                          mesh.cellTypes.size() * sizeof(CellType) +
                          mesh.cellOffsets.size() * sizeof(std::uint64_t) +
                          mesh.cellIndices.size() * sizeof(std::uint32_t);
    for (const Field& f : mesh.fields) bytes += f.values.size() * sizeof(float) + f.name.size();
    return bytes;
}

}  // namespace uvr

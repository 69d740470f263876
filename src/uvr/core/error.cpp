// SPDX-License-Identifier: MIT
#include "uvr/core/error.h"

namespace uvr {

void throwParseError(const std::string& file, const std::string& where,
                     const std::string& message) {
    throw Error(ErrorKind::Parse, file + ": " + where + ": " + message);
}

void throwError(ErrorKind kind, const std::string& file, const std::string& message) {
    throw Error(kind, file.empty() ? message : file + ": " + message);
}

std::string atLine(std::uint64_t line) {
    return "line " + std::to_string(line);
}
std::string atByte(std::uint64_t offset) {
    return "byte " + std::to_string(offset);
}

namespace detail {
void checkFailed(const char* expr, const char* file, int line, const std::string& msg) {
    throw Error(ErrorKind::Internal, std::string("internal check failed: ") + expr + " at " + file +
                                         ":" + std::to_string(line) +
                                         (msg.empty() ? "" : ": " + msg));
}
}  // namespace detail

}  // namespace uvr

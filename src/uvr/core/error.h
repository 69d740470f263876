// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

namespace uvr {

/// What kind of failure an Error reports; the CLI maps every kind to exit code 2 except Internal.
enum class ErrorKind {
    Io,           ///< a file could not be opened, read or written
    Parse,        ///< a file is malformed (names file and line/byte offset)
    Validation,   ///< a mesh is structurally invalid (names the element index)
    Argument,     ///< a flag or parameter is out of range or malformed
    Unsupported,  ///< valid input uvr does not handle (names the feature)
    Resource,     ///< an allocation would exceed the file size or the memory limit
    Internal,     ///< a broken invariant inside uvr (a bug)
};

/// The one exception type of the library: a one-line message naming what and where.
class Error : public std::runtime_error {
public:
    Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    /// The category of the failure.
    ErrorKind kind() const { return kind_; }

private:
    ErrorKind kind_;
};

/// Throws a Parse error "FILE: WHERE: MESSAGE" (WHERE e.g. "line 12" or "byte 4096").
[[noreturn]] void throwParseError(const std::string& file, const std::string& where,
                                  const std::string& message);
/// Throws an error of the given kind with "FILE: MESSAGE" (file may be empty).
[[noreturn]] void throwError(ErrorKind kind, const std::string& file, const std::string& message);
/// Formats "line N".
std::string atLine(std::uint64_t line);
/// Formats "byte N".
std::string atByte(std::uint64_t offset);

namespace detail {
[[noreturn]] void checkFailed(const char* expr, const char* file, int line, const std::string& msg);
}  // namespace detail

}  // namespace uvr

/// Invariant check, always compiled in; throws Error(Internal) with the expression and message.
#define UVR_CHECK(cond, msg)                                                            \
    do {                                                                                \
        if (!(cond)) {                                                                  \
            std::ostringstream uvr_check_os_;                                           \
            uvr_check_os_ << msg;                                                       \
            ::uvr::detail::checkFailed(#cond, __FILE__, __LINE__, uvr_check_os_.str()); \
        }                                                                               \
    } while (0)

/// Debug-only invariant check.
#ifdef NDEBUG
#define UVR_DCHECK(cond, msg) \
    do {                      \
    } while (0)
#else
#define UVR_DCHECK(cond, msg) UVR_CHECK(cond, msg)
#endif

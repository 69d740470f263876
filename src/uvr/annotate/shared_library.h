// SPDX-License-Identifier: MIT
#pragma once

#include <string>

namespace uvr {

/// A shared library opened at run time (dlopen) rather than linked: a binary built here and
/// carried to a machine without the library still starts, and only the feature that needs it
/// fails, with a message naming the package to install. It stays loaded for the process.
class SharedLibrary {
public:
    /// Opens `soname` (e.g. "libfreetype.so.6"); throws Error(Unsupported) "SONAME cannot be
    /// loaded (REASON): install the Debian package PACKAGE".
    SharedLibrary(const std::string& soname, const std::string& package);
    SharedLibrary(const SharedLibrary&) = delete;
    SharedLibrary& operator=(const SharedLibrary&) = delete;

    /// The address of an exported function or object; throws Error(Unsupported) naming the
    /// library and the symbol when it has none of that name (a version too old).
    void* symbol(const char* name) const;

    /// symbol(name) as a function pointer of the type of `f`'s declaration.
    template <typename F>
    F* function(const char* name) const {
        return reinterpret_cast<F*>(symbol(name));
    }

private:
    std::string soname_, package_;
    void* handle_ = nullptr;
};

}  // namespace uvr

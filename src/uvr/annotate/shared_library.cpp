// SPDX-License-Identifier: MIT
#include "uvr/annotate/shared_library.h"

#include <dlfcn.h>

#include "uvr/core/error.h"

namespace uvr {

SharedLibrary::SharedLibrary(const std::string& soname, const std::string& package)
    : soname_(soname), package_(package) {
    // Never closed: pointers into it live as long as the process.
    handle_ = ::dlopen(soname.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle_) {
        const char* reason = ::dlerror();
        throwError(ErrorKind::Unsupported, "",
                   soname + " cannot be loaded (" + std::string(reason ? reason : "not found") +
                       "): install the Debian package " + package);
    }
}

void* SharedLibrary::symbol(const char* name) const {
    ::dlerror();
    void* p = ::dlsym(handle_, name);
    if (!p)
        throwError(ErrorKind::Unsupported, "",
                   soname_ + " has no " + name + ": install a newer " + package_);
    return p;
}

}  // namespace uvr

// SPDX-License-Identifier: MIT
// Large allocations of the uvr executable on transparent huge pages (issue 16).
//
// Preparing 100M tetrahedra writes about 8 GB of fresh memory (the mesh as read, the split, the
// neighbour table, partitions, grids). On 4 KiB pages that is two million page faults, about
// 2 s of a 10 s first image on the GPU machine, whose kernel gives huge pages only where a
// program asks for them (transparent_hugepage=madvise, Debian's default). So the global
// operator new puts every allocation of at least kHugeAllocationBytes (32 MiB) on 2 MiB
// boundaries and asks for huge pages there (madvise MADV_HUGEPAGE). Everything else goes to
// malloc unchanged, and operator delete stays the default (free), which frees both. (The new
// forms not replaced here, arrays and nothrow, call this one.)
//
// UVR_HUGE_PAGES=0 in the environment turns it off. Sanitizer builds leave operator new to the
// sanitizer (which checks new/delete pairs).
#include "huge_pages.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

#ifndef UVR_NO_HUGE_PAGES

namespace {

using uvr::cli::kHugeAllocationBytes;
using uvr::cli::kHugePageBytes;

/// Whether huge pages are wanted (UVR_HUGE_PAGES is not "0"); read once.
bool hugePagesWanted() {
    static const bool wanted = [] {
        const char* v = std::getenv("UVR_HUGE_PAGES");
        return !(v && std::strcmp(v, "0") == 0);
    }();
    return wanted;
}

/// malloc's memory, or huge-page-aligned memory advised for huge pages when `size` is large;
/// nullptr when there is none.
void* allocate(std::size_t size) {
    if (size >= kHugeAllocationBytes && size <= SIZE_MAX - kHugePageBytes && hugePagesWanted()) {
        const std::size_t rounded = (size + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
        void* p = std::aligned_alloc(kHugePageBytes, rounded);
        if (p) madvise(p, rounded, MADV_HUGEPAGE);  // a hint: no huge pages is no error
        return p;
    }
    return std::malloc(size ? size : 1);
}

}  // namespace

void* operator new(std::size_t size) {
    for (;;) {
        if (void* p = allocate(size)) return p;
        const std::new_handler handler = std::get_new_handler();
        if (!handler) throw std::bad_alloc();
        handler();
    }
}

#endif

// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace uvr {

/// An allocator whose value-less construct default-initialises (leaves trivial types
/// uninitialised), so resizing a large scratch array does not zero it on one thread: the parallel
/// loop that fills it touches its pages first.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    DefaultInitAllocator() noexcept = default;
    template <class U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
    /// Default-initialises (no zeroing of trivial types).
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    /// Constructs from arguments, as std::allocator does.
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// A std::vector for large scratch arrays of plain data whose every element is written before it
/// is read (resize leaves new trivial elements uninitialised).
template <class T>
using ScratchVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace uvr

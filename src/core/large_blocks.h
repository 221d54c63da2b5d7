// Large arrays (volumes, per-voxel and per-pixel buffers), recycled between frames.
//
// A frame allocates and frees a few hundred MiB of such arrays; fresh pages from the kernel must be faulted
// in and zeroed by it every time, which was a seventh of a frame's time. Freed blocks are therefore kept (up
// to kMaxKeptBytes) and handed out again for the next allocation of the same size. A new block is 2 MiB
// aligned, asked for in transparent huge pages (madvise MADV_HUGEPAGE, which the kernel's default policy
// "madvise" honours) and faulted in by one system call when it is mapped (MADV_POPULATE_WRITE). In the
// virtual machines this project runs on, a fresh 4 KiB page costs about 10 us, nearly all of it the host
// backing the page: 256 MiB took 710-825 ms to touch in 4 KiB pages, 500-570 ms populated in 4 KiB pages,
// 30-60 ms in huge pages right after another process freed memory, and 210-740 ms in huge pages after a
// pause of 6 s (the machine gives freed memory back to its host). Where the kernel has no free huge page at
// hand it compacts memory first or falls back to 4 KiB pages, so a process's first blocks vary in cost from
// run to run (docs/performance.md, "Single renders").
// Smaller arrays go to the usual allocator, which retainFreedMemory() (deltagi/renderer.h, defined here)
// tells to keep what is freed.
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <utility>

namespace deltagi {

inline constexpr size_t kLargeBlockBytes = size_t(2) << 20;  // from this size on, and the alignment
inline constexpr size_t kMaxKeptBytes = size_t(1) << 30;     // freed blocks kept for reuse, at most

// A block of at least `bytes` (>= kLargeBlockBytes), 2 MiB aligned; throws std::bad_alloc.
void* allocateLargeBlock(size_t bytes);
// Gives a block back (same `bytes` as allocated): kept for reuse, or returned to the system.
void freeLargeBlock(void* block, size_t bytes);

template <typename T>
struct LargeBlockAllocator {
    using value_type = T;
    LargeBlockAllocator() = default;
    template <typename U>
    LargeBlockAllocator(const LargeBlockAllocator<U>&) {}
    T* allocate(size_t count) {
        const size_t bytes = count * sizeof(T);
        if (bytes < kLargeBlockBytes) return std::allocator<T>().allocate(count);
        return static_cast<T*>(allocateLargeBlock(bytes));
    }
    void deallocate(T* p, size_t count) {
        const size_t bytes = count * sizeof(T);
        if (bytes < kLargeBlockBytes) return std::allocator<T>().deallocate(p, count);
        freeLargeBlock(p, bytes);
    }
    template <typename U>
    bool operator==(const LargeBlockAllocator<U>&) const {
        return true;
    }
};

// LargeBlockAllocator whose elements made without a value are left uninitialized (an integer, a glm vector
// without GLM_FORCE_CTOR_INIT, a struct of them without default member initializers): for arrays that are
// written in full next.
template <typename T>
struct UnsetAllocator : LargeBlockAllocator<T> {
    using value_type = T;
    template <typename U>
    struct rebind {
        using other = UnsetAllocator<U>;
    };
    UnsetAllocator() = default;
    template <typename U>
    UnsetAllocator(const UnsetAllocator<U>&) {}
    template <typename U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

}  // namespace deltagi

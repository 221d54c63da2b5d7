// Large arrays (volumes, per-voxel and per-pixel buffers), recycled between frames.
//
// A frame allocates and frees a few hundred MiB of such arrays; fresh pages from the kernel must be faulted
// in and zeroed by it every time, which was a seventh of a frame's time. Freed blocks are therefore kept (up
// to kMaxKeptBytes) and handed out again for the next allocation of the same size; a new block's pages are
// faulted in by one system call when it is mapped (a process's first render, `deltagi render
// examples/cornell-buddha.json`: 236,000 page faults -> 92,000, 3.26 -> 2.65 s). Blocks are 2 MiB aligned,
// so that the kernel may back them with transparent huge pages where its policy is "always". (Asking for huge
// pages with madvise was tried: with the "madvise" defrag policy of this project's machines, the first touch
// of new blocks then stalled in page compaction, doubling a single render's time in one run out of two.)
// Small arrays go to the usual allocator.
#pragma once

#include <cstddef>
#include <memory>

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

}  // namespace deltagi

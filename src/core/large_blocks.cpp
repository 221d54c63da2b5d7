#include "core/large_blocks.h"

#include "deltagi/renderer.h"

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <new>

#include <sys/mman.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace deltagi {

namespace {

size_t roundedUp(size_t bytes, size_t step) {
    return (bytes + step - 1) / step * step;
}

// A block's size class: whole 2 MiB up to 16 MiB, then eight classes per doubling (at most 1/8 more than
// asked for), so that arrays whose size changes a little from frame to frame (a shadow map's texels, the
// objects' windowed volumes) find a freed block of their class.
size_t roundedSize(size_t bytes) {
    const size_t size = roundedUp(bytes, kLargeBlockBytes);
    if (size <= 8 * kLargeBlockBytes) return size;
    return roundedUp(size, std::bit_floor(size) / 8);
}

// Freed blocks by rounded size. Never destroyed: blocks may be freed by static objects' destructors.
struct KeptBlocks {
    std::mutex mutex;
    std::multimap<size_t, void*> blocks;
    size_t bytes = 0;
};
KeptBlocks& kept() {
    static auto* k = new KeptBlocks;
    return *k;
}

}  // namespace

void* allocateLargeBlock(size_t bytes) {
    const size_t size = roundedSize(bytes);
    {
        KeptBlocks& k = kept();
        std::lock_guard lock(k.mutex);
        if (auto it = k.blocks.find(size); it != k.blocks.end()) {
            void* block = it->second;
            k.blocks.erase(it);
            k.bytes -= size;
            return block;
        }
    }
    // A mapping of its own, trimmed to 2 MiB alignment, in huge pages where the kernel has them, faulted in
    // at once: one system call instead of a page fault at every first touch (see the header). A kernel
    // older than Linux 5.14 (no MADV_POPULATE_WRITE) faults them as they are touched.
    const size_t mapped = size + kLargeBlockBytes;
    void* p = mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    const uintptr_t start = reinterpret_cast<uintptr_t>(p);
    const uintptr_t aligned = (start + kLargeBlockBytes - 1) / kLargeBlockBytes * kLargeBlockBytes;
    if (aligned > start) munmap(p, aligned - start);
    const uintptr_t end = start + mapped, blockEnd = aligned + size;
    if (end > blockEnd) munmap(reinterpret_cast<void*>(blockEnd), end - blockEnd);
#ifdef MADV_HUGEPAGE
    madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);
#endif
#ifdef MADV_POPULATE_WRITE
    madvise(reinterpret_cast<void*>(aligned), size, MADV_POPULATE_WRITE);
#endif
    return reinterpret_cast<void*>(aligned);
}

void freeLargeBlock(void* block, size_t bytes) {
    if (!block) return;
    const size_t size = roundedSize(bytes);
    {
        KeptBlocks& k = kept();
        std::lock_guard lock(k.mutex);
        if (k.bytes + size <= kMaxKeptBytes) {
            k.blocks.emplace(size, block);
            k.bytes += size;
            return;
        }
    }
    munmap(block, size);
}

void retainFreedMemory() {
#if defined(__GLIBC__)
    // Blocks under 32 MiB (glibc's largest mmap threshold) come from the heap, whose freed memory is never
    // given back: without this, glibc maps a block of a few MiB afresh every time once its dynamic threshold
    // and the heap's trimming disagree, as a 1280x960 frame's per-pixel arrays did.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
#endif
}

}  // namespace deltagi

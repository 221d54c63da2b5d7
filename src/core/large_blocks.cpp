#include "core/large_blocks.h"

#include <cstdlib>
#include <map>
#include <mutex>
#include <new>

namespace deltagi {

namespace {

size_t roundedSize(size_t bytes) {
    return (bytes + kLargeBlockBytes - 1) / kLargeBlockBytes * kLargeBlockBytes;
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
    void* block = std::aligned_alloc(kLargeBlockBytes, size);
    if (!block) throw std::bad_alloc();
    return block;
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
    std::free(block);
}

}  // namespace deltagi

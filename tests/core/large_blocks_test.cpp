// The large blocks of core/large_blocks.h: aligned, and recycled by size class.
#include "core/large_blocks.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "deltagi/renderer.h"

namespace deltagi {
namespace {

constexpr size_t kMiB = size_t(1) << 20;

TEST(LargeBlocks, AreAlignedToTwoMiBAndWritable) {
    const size_t bytes = 3 * kMiB + 1;
    void* block = allocateLargeBlock(bytes);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % kLargeBlockBytes, 0u);
    std::memset(block, 0xab, bytes);
    EXPECT_EQ(static_cast<unsigned char*>(block)[bytes - 1], 0xab);
    freeLargeBlock(block, bytes);
}

// A freed block serves the next array of its size class: whole 2 MiB up to 16 MiB, then steps of 1/8 of
// the power of two below (33 and 35 MiB are both 36; 37 MiB is 40).
TEST(LargeBlocks, AFreedBlockServesTheNextArrayOfItsSizeClass) {
    void* block = allocateLargeBlock(33 * kMiB);
    freeLargeBlock(block, 33 * kMiB);
    void* again = allocateLargeBlock(35 * kMiB);
    EXPECT_EQ(again, block);
    std::memset(again, 1, 35 * kMiB);  // the whole class is mapped
    freeLargeBlock(again, 35 * kMiB);
    void* larger = allocateLargeBlock(37 * kMiB);
    EXPECT_NE(larger, block);
    freeLargeBlock(larger, 37 * kMiB);

    void* small = allocateLargeBlock(5 * kMiB);
    freeLargeBlock(small, 5 * kMiB);
    void* nextSmall = allocateLargeBlock(6 * kMiB - 1);
    EXPECT_EQ(nextSmall, small);
    freeLargeBlock(nextSmall, 6 * kMiB - 1);
    void* otherSmall = allocateLargeBlock(6 * kMiB + 1);
    EXPECT_NE(otherSmall, small);
    freeLargeBlock(otherSmall, 6 * kMiB + 1);
}

#if defined(__GLIBC__)
// AddressSanitizer's runtime, present where the test binary is linked with it (the sanitizer build, whose
// test sources are not instrumented: no macro says so). Its allocator replaces glibc's.
extern "C" void __asan_init() __attribute__((weak));

// After retainFreedMemory() an array of 24 MiB comes from the heap, not a mapping of its own, and the heap
// keeps it when it is freed: the next one of that size touches no fresh page. (glibc's own settings map it,
// and give a freed heap top back beyond 128 KiB, until a freed mapping of that size raises its thresholds.)
TEST(RetainFreedMemory, KeepsAFreedArrayInTheHeapForTheNext) {
    if (__asan_init != nullptr) GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's";
    retainFreedMemory();
    const size_t bytes = 24 * kMiB;
    const struct mallinfo2 before = mallinfo2();
    void* block = std::malloc(bytes);
    ASSERT_NE(block, nullptr);
    std::memset(block, 1, bytes);
    const struct mallinfo2 holding = mallinfo2();
    EXPECT_EQ(holding.hblkhd, before.hblkhd);  // no mapping of its own
    EXPECT_GE(holding.arena, before.arena + bytes - 1 * kMiB);
    std::free(block);
    EXPECT_GE(mallinfo2().arena, holding.arena);  // not trimmed
}
#endif

}  // namespace
}  // namespace deltagi

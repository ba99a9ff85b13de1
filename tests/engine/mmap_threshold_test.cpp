// The allocator policy a server sets: big blocks stay mapped on their own after one was freed, so
// freeing them returns the memory (glibc's dynamic threshold would keep the next one in the heap).

#include "engine/core/memory_trim.h"

#include <malloc.h>

#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

namespace strata {
namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool SANITIZED = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool SANITIZED = true;
#else
constexpr bool SANITIZED = false;
#endif
#else
constexpr bool SANITIZED = false;
#endif

/// Allocates `bytes`, touches every page, and returns the block (volatile stores: the pair of
/// malloc and free must not be optimised away).
char* touched_block(std::size_t bytes) {
    auto* p = static_cast<char*>(std::malloc(bytes));
    volatile char* v = p;
    for (std::size_t i = 0; i < bytes; i += 4096) v[i] = 1;
    return p;
}

/// Mapped blocks now held by malloc.
std::size_t mapped_blocks() {
    return mallinfo2().hblks;
}

TEST(MmapThreshold, ABigBlockFreedLeavesTheNextOneMappedOnItsOwn) {
    if (SANITIZED) GTEST_SKIP() << "a sanitizer's allocator replaces glibc's";
    ASSERT_EQ(std::getenv("GLIBC_TUNABLES"), nullptr);
    ASSERT_EQ(std::getenv("MALLOC_MMAP_THRESHOLD_"), nullptr);
    ASSERT_TRUE(fix_mmap_threshold());
    const std::size_t bytes = 4 * MMAP_THRESHOLD_BYTES;
    const std::size_t before = mapped_blocks();
    char* first = touched_block(bytes);
    if (mapped_blocks() == before) {
        // Run with other tests in one process, the heap may already hold a free chunk this
        // big, which malloc reuses before it considers mapping; CTest runs this test alone.
        std::free(first);
        GTEST_SKIP() << "the heap already had a free chunk of " << bytes << " bytes";
    }
    std::free(first);
    // Unfixed, glibc would now raise its threshold past `bytes` and take this one from the heap.
    char* second = touched_block(bytes);
    EXPECT_EQ(mapped_blocks(), before + 1);
    std::free(second);
    EXPECT_EQ(mapped_blocks(), before);
    // A small block still comes from the heap.
    char* small = touched_block(MMAP_THRESHOLD_BYTES / 4);
    EXPECT_EQ(mapped_blocks(), before);
    std::free(small);
}

TEST(MmapThreshold, AThresholdChosenInTheEnvironmentIsKept) {
    ASSERT_EQ(setenv("GLIBC_TUNABLES", "glibc.malloc.mmap_threshold=65536", 1), 0);
    EXPECT_FALSE(fix_mmap_threshold());
    unsetenv("GLIBC_TUNABLES");
    ASSERT_EQ(setenv("MALLOC_MMAP_THRESHOLD_", "65536", 1), 0);
    EXPECT_FALSE(fix_mmap_threshold());
    unsetenv("MALLOC_MMAP_THRESHOLD_");
}

}  // namespace
}  // namespace strata

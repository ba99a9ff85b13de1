#pragma once
// Giving freed memory back to the system. glibc keeps what a program frees in its malloc arenas
// (one per thread that allocated, and Embree builds allocate on every TBB worker): after a large
// scene is removed the process would stay at its peak size. Large releases trim the arenas, and
// a server fixes the mmap threshold so that big transient arrays never enter them.

#include <cstddef>

namespace strata {

/// Returns free heap memory to the system (malloc_trim). Costs about a millisecond per GiB of
/// heap: call it after large releases, not after every small one.
void release_free_memory();

/// Bytes a release must free at least before release_free_memory() is worth its cost.
constexpr std::size_t TRIM_THRESHOLD_BYTES = std::size_t(16) << 20;

/// Blocks of at least this many bytes are mapped on their own and unmapped when freed.
constexpr std::size_t MMAP_THRESHOLD_BYTES = std::size_t{1} << 20;

/// Fixes glibc's mmap threshold at MMAP_THRESHOLD_BYTES, unless GLIBC_TUNABLES or
/// MALLOC_MMAP_THRESHOLD_ chose one. By default glibc raises the threshold to the size of each
/// mapped block freed, so after the first big transient array (a bulk edit's decoded transforms
/// and undo records) later ones come from the heap, and the holes they leave between long-lived
/// records stay resident. A process-wide choice: for a program's main(). Returns whether it set
/// the threshold.
bool fix_mmap_threshold();

}  // namespace strata

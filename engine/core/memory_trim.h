#pragma once
// Giving freed memory back to the system. glibc keeps what a program frees in its malloc arenas
// (one per thread that allocated, and Embree builds allocate on every TBB worker): after a large
// scene is removed the process would stay at its peak size. Large releases trim the arenas.

#include <cstddef>

namespace strata {

/// Returns free heap memory to the system (malloc_trim). Costs about a millisecond per GiB of
/// heap: call it after large releases, not after every small one.
void release_free_memory();

/// Bytes a release must free at least before release_free_memory() is worth its cost.
constexpr std::size_t TRIM_THRESHOLD_BYTES = std::size_t(16) << 20;

}  // namespace strata

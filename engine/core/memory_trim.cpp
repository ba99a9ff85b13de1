#include "engine/core/memory_trim.h"

#include <malloc.h>

#include <cstdlib>
#include <string_view>

namespace strata {

void release_free_memory() {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}

bool fix_mmap_threshold() {
#if defined(__GLIBC__)
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (tunables && std::string_view(tunables).find("mmap_threshold") != std::string_view::npos)
        return false;
    if (std::getenv("MALLOC_MMAP_THRESHOLD_")) return false;
    return mallopt(M_MMAP_THRESHOLD, int(MMAP_THRESHOLD_BYTES)) == 1;
#else
    return false;
#endif
}

}  // namespace strata

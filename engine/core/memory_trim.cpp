#include "engine/core/memory_trim.h"

#include <malloc.h>

namespace strata {

void release_free_memory() {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
}

}  // namespace strata

#pragma once
// Invariant checks (pbrt-v4 style). A failed STRATA_CHECK is a bug in Strata, never bad input:
// input errors are returned as values (see result.h).

#include <cstdio>
#include <cstdlib>

namespace strata::detail {
[[noreturn]] inline void check_failed(const char* expr, const char* file, int line) {
    std::fprintf(stderr, "strata: internal check failed: %s (%s:%d)\n", expr, file, line);
    std::abort();
}
}  // namespace strata::detail

#define STRATA_CHECK(expr) \
    ((expr) ? (void)0 : ::strata::detail::check_failed(#expr, __FILE__, __LINE__))

#ifndef NDEBUG
#define STRATA_DCHECK(expr) STRATA_CHECK(expr)
#else
#define STRATA_DCHECK(expr) ((void)0)
#endif

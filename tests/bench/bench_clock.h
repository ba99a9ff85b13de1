#pragma once
// Wall-clock helpers of the plain-program benchmarks: milliseconds now, and the median of runs.

#include <algorithm>
#include <chrono>
#include <vector>

namespace strata::bench {

inline double now_ms() {
    return std::chrono::duration<double, std::milli>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

}  // namespace strata::bench

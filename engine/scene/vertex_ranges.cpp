#include "engine/scene/vertex_ranges.h"

#include <algorithm>
#include <limits>

namespace strata {

void VertexRanges::add(uint32_t begin, uint32_t end) {
    if (begin >= end) return;
    // Step: find the ranges the new one overlaps or touches, and fold them into it.
    auto first = std::lower_bound(m_ranges.begin(), m_ranges.end(), begin,
                                  [](const Range& r, uint32_t v) { return r.end < v; });
    auto last = first;
    while (last != m_ranges.end() && last->begin <= end) {
        begin = std::min(begin, last->begin);
        end = std::max(end, last->end);
        ++last;
    }
    first = m_ranges.erase(first, last);
    m_ranges.insert(first, Range{begin, end});
    // Step: keep the list short.
    if (m_ranges.size() > MAX_RANGES) merge_closest();
}

void VertexRanges::merge_closest() {
    std::size_t best = 0;
    uint32_t best_gap = std::numeric_limits<uint32_t>::max();
    for (std::size_t i = 0; i + 1 < m_ranges.size(); ++i) {
        const uint32_t gap = m_ranges[i + 1].begin - m_ranges[i].end;
        if (gap < best_gap) {
            best_gap = gap;
            best = i;
        }
    }
    m_ranges[best].end = m_ranges[best + 1].end;
    m_ranges.erase(m_ranges.begin() + std::ptrdiff_t(best) + 1);
}

uint64_t VertexRanges::count() const {
    uint64_t n = 0;
    for (const Range& r : m_ranges) n += r.end - r.begin;
    return n;
}

}  // namespace strata

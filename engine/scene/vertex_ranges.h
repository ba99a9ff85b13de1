#pragma once
// The vertices of a mesh whose positions changed since the last commit, as a short list of
// ranges. A clustered BLAS (engine/accel/cluster_layout.h) refits only the clusters these ranges
// touch, so a batch that moves a few scattered patches of a big mesh must not read as one range
// from the first patch to the last.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace strata {

/// Sorted, disjoint, non-adjacent vertex ranges [begin, end). Past MAX_RANGES the two ranges
/// with the smallest gap merge, so the list may cover more vertices than were written, never
/// fewer.
class VertexRanges {
public:
    struct Range {
        uint32_t begin = 0;
        uint32_t end = 0;

        friend bool operator==(const Range&, const Range&) = default;
    };

    static constexpr std::size_t MAX_RANGES = 1024;

    /// Adds [begin, end); an empty range changes nothing.
    void add(uint32_t begin, uint32_t end);
    void clear() { m_ranges.clear(); }

    bool empty() const { return m_ranges.empty(); }
    std::span<const Range> ranges() const { return m_ranges; }
    /// First vertex covered (UINT32_MAX when empty) and one past the last (0 when empty).
    uint32_t begin() const { return m_ranges.empty() ? UINT32_MAX : m_ranges.front().begin; }
    uint32_t end() const { return m_ranges.empty() ? 0 : m_ranges.back().end; }
    /// Vertices covered.
    uint64_t count() const;

    friend bool operator==(const VertexRanges&, const VertexRanges&) = default;

private:
    void merge_closest();

    std::vector<Range> m_ranges;
};

}  // namespace strata

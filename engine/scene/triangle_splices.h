#pragma once
// The triangles of a mesh replaced since the last commit (local topology edits), kept as
// disjoint runs of the numbering at the last commit: run k's triangles [old_first, old_end) were
// replaced by `count` triangles. Triangles outside the runs are unchanged and only renumbered:
// each moves by the runs before it. Edits that overlap or touch a run merge into it; past
// MAX_RUNS (a patch re-cut row by row, a thousand rows) the two closest runs merge, taking the
// unchanged triangles between them along (a run may hold unchanged triangles, never miss a
// replaced one).

#include <cstdint>
#include <optional>
#include <vector>

namespace strata {

class TriangleSplices {
public:
    static constexpr std::size_t MAX_RUNS = 1024;

    struct Run {
        uint32_t old_first = 0;  ///< numbering at the last commit
        uint32_t old_end = 0;
        uint32_t count = 0;  ///< triangles standing in its place now

        uint32_t old_count() const { return old_end - old_first; }
        friend bool operator==(const Run&, const Run&) = default;
    };

    /// Adds an edit that replaced triangles [at, at + removed) of the numbering now with
    /// `inserted` new ones.
    void add(uint32_t at, uint32_t removed, uint32_t inserted);

    bool empty() const { return m_runs.empty(); }
    /// Sorted by old_first, disjoint.
    const std::vector<Run>& runs() const { return m_runs; }
    /// Triangles the runs replaced, and triangles standing in their places now.
    uint64_t old_count() const;
    uint64_t new_count() const;
    /// Where run `k` starts now (its new triangles are [start(k), start(k) + count)).
    std::vector<uint32_t> starts() const;
    friend bool operator==(const TriangleSplices&, const TriangleSplices&) = default;

private:
    void merge_closest();

    std::vector<Run> m_runs;
};

/// Maps the numbering of the last commit to the numbering now, in O(log runs) per triangle.
class TriangleRenumbering {
public:
    explicit TriangleRenumbering(const TriangleSplices& splices);
    /// The number now of triangle `old` of the last commit, or nullopt when a run replaced it.
    std::optional<uint32_t> operator()(uint32_t old) const;
    /// Whether a run replaced triangle `old`.
    bool replaced(uint32_t old) const { return !(*this)(old); }
    /// Whether any triangle's number changes.
    bool moves() const {
        for (uint32_t s : m_shift)
            if (s != 0) return true;
        return false;
    }

private:
    std::vector<uint32_t> m_old_first;
    std::vector<uint32_t> m_old_end;
    std::vector<uint32_t> m_shift;  ///< added to triangles after run k (and before run k + 1)
};

}  // namespace strata

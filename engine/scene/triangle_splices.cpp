#include "engine/scene/triangle_splices.h"

#include <algorithm>
#include <limits>

namespace strata {

namespace {

int64_t delta(const TriangleSplices::Run& r) { return int64_t(r.count) - int64_t(r.old_count()); }

}  // namespace

void TriangleSplices::add(uint32_t at, uint32_t removed, uint32_t inserted) {
    if (removed == 0 && inserted == 0) return;
    const int64_t lo = at, hi = int64_t(at) + removed;  // numbering now
    // Step: skip the runs that end before the edit (a run ending at `lo` touches it: merged).
    std::size_t i = 0;
    int64_t shift = 0;  // how far the runs before run i moved the numbering
    while (i < m_runs.size() && int64_t(m_runs[i].old_first) + shift + m_runs[i].count < lo) {
        shift += delta(m_runs[i]);
        ++i;
    }
    // Step: the runs the edit overlaps or touches merge with it into one.
    Run merged{uint32_t(lo - shift), 0, 0};
    int64_t now_lo = lo, now_hi = hi, shift_after = shift;
    std::size_t j = i;
    while (j < m_runs.size() && int64_t(m_runs[j].old_first) + shift_after <= hi) {
        const int64_t first = int64_t(m_runs[j].old_first) + shift_after;
        if (first < now_lo) {
            now_lo = first;
            merged.old_first = m_runs[j].old_first;
        }
        now_hi = std::max(now_hi, first + m_runs[j].count);
        shift_after += delta(m_runs[j]);
        ++j;
    }
    // now_hi is either the edit's end or a merged run's end: both map back with shift_after.
    merged.old_end = uint32_t(now_hi - shift_after);
    merged.count = uint32_t(now_hi - now_lo - removed + inserted);
    m_runs.erase(m_runs.begin() + std::ptrdiff_t(i), m_runs.begin() + std::ptrdiff_t(j));
    // Triangles inserted and removed again leave nothing to do.
    if (merged.old_count() != 0 || merged.count != 0)
        m_runs.insert(m_runs.begin() + std::ptrdiff_t(i), merged);
    while (m_runs.size() > MAX_RUNS) merge_closest();
}

void TriangleSplices::merge_closest() {
    std::size_t best = 0;
    uint32_t gap = std::numeric_limits<uint32_t>::max();
    for (std::size_t k = 0; k + 1 < m_runs.size(); ++k) {
        const uint32_t g = m_runs[k + 1].old_first - m_runs[k].old_end;
        if (g < gap) {
            gap = g;
            best = k;
        }
    }
    Run& a = m_runs[best];
    const Run& b = m_runs[best + 1];
    a.count += gap + b.count;  // the unchanged triangles between them count as replaced
    a.old_end = b.old_end;
    m_runs.erase(m_runs.begin() + std::ptrdiff_t(best) + 1);
}

uint64_t TriangleSplices::old_count() const {
    uint64_t n = 0;
    for (const Run& r : m_runs) n += r.old_count();
    return n;
}

uint64_t TriangleSplices::new_count() const {
    uint64_t n = 0;
    for (const Run& r : m_runs) n += r.count;
    return n;
}

std::vector<uint32_t> TriangleSplices::starts() const {
    std::vector<uint32_t> out;
    out.reserve(m_runs.size());
    int64_t shift = 0;
    for (const Run& r : m_runs) {
        out.push_back(uint32_t(int64_t(r.old_first) + shift));
        shift += delta(r);
    }
    return out;
}

TriangleRenumbering::TriangleRenumbering(const TriangleSplices& splices) {
    int64_t shift = 0;
    for (const TriangleSplices::Run& r : splices.runs()) {
        shift += delta(r);
        m_old_first.push_back(r.old_first);
        m_old_end.push_back(r.old_end);
        m_shift.push_back(uint32_t(shift));  // unsigned wrap-around: may move down
    }
}

std::optional<uint32_t> TriangleRenumbering::operator()(uint32_t old) const {
    // Most triangles lie before the first run or after the last.
    if (m_old_first.empty() || old < m_old_first.front()) return old;
    if (old >= m_old_end.back()) return old + m_shift.back();
    // The last run starting at or before `old`.
    const auto it = std::upper_bound(m_old_first.begin(), m_old_first.end(), old);
    if (it == m_old_first.begin()) return old;
    const auto k = std::size_t(it - m_old_first.begin()) - 1;
    if (old < m_old_end[k]) return std::nullopt;
    return old + m_shift[k];
}

}  // namespace strata

#include "engine/accel/cluster_layout.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

namespace strata {

namespace {

/// Spreads the low 10 bits of `x` three apart.
uint32_t spread_bits(uint32_t x) {
    x &= 0x3FFu;
    x = (x | (x << 16)) & 0x030000FFu;
    x = (x | (x << 8)) & 0x0300F00Fu;
    x = (x | (x << 4)) & 0x030C30C3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
}

Vec3 centroid(std::span<const Vec3> p, const Triangle& t) {
    return (p[t.x] + p[t.y] + p[t.z]) * (1.0f / 3.0f);
}

Bounds3 centroid_bounds(std::span<const Vec3> p, std::span<const Triangle> t) {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, t.size(), 16384), Bounds3{},
        [&](const tbb::blocked_range<std::size_t>& r, Bounds3 b) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) b.extend(centroid(p, t[i]));
            return b;
        },
        [](Bounds3 a, const Bounds3& b) {
            a.extend(b);
            return a;
        });
}

}  // namespace

uint32_t ClusterPolicy::cluster_size(std::size_t triangles) const {
    const double size = size_factor * std::sqrt(double(triangles));
    return static_cast<uint32_t>(
        std::clamp(size, double(std::max<uint32_t>(min_size, 1)), double(std::max(max_size, 1u))));
}

ClusterLayout::ClusterLayout(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                             uint32_t cluster_size) {
    const std::size_t n = triangles.size();

    // Step: sort triangles by the Morton code of their centroids (ties by index: deterministic).
    const Bounds3 box = centroid_bounds(positions, triangles);
    // One scale for all axes: cubic cells, so a thin axis does not count as much as a long one.
    const Vec3 extent = box.extent();
    const float scale = 1023.0f / std::max({extent.x, extent.y, extent.z, 1e-30f});
    std::vector<uint64_t> keys(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              const Vec3 q = glm::clamp((centroid(positions, triangles[i]) -
                                                         box.lower) * scale,
                                                        Vec3(0.0f), Vec3(1023.0f));
                              const uint32_t code = spread_bits(uint32_t(q.x)) |
                                                    (spread_bits(uint32_t(q.y)) << 1) |
                                                    (spread_bits(uint32_t(q.z)) << 2);
                              keys[i] = (uint64_t(code) << 32) | i;
                          }
                      });
    tbb::parallel_sort(keys.begin(), keys.end());
    cut(keys, std::max<uint32_t>(cluster_size, 1));
    m_order.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              m_order[i] = static_cast<uint32_t>(keys[i]);
                      });

    // Step: each cluster's size and triangles, then the vertex-to-cluster map.
    m_cut_size = std::max<uint32_t>(cluster_size, 1);
    m_triangle_count = static_cast<uint32_t>(n);
    const uint32_t count = static_cast<uint32_t>(m_first.size() - 1);
    m_size.resize(count);
    m_ids.resize(count);
    m_remade.assign(count, 0);
    m_own.resize(count);
    for (uint32_t c = 0; c < count; ++c) {
        m_size[c] = m_first[c + 1] - m_first[c];
        m_ids[c] = m_order.data() + m_first[c];
    }
    map_vertices(triangles, positions.size());
}

void ClusterLayout::map_vertices(std::span<const Triangle> triangles, std::size_t vertices) {
    // Clusters are visited in order, so each vertex's list comes out ascending and a vertex used
    // twice by one cluster is counted once.
    std::vector<uint32_t> last(vertices, UINT32_MAX);
    m_vertex_offsets.assign(vertices + 1, 0);
    auto visit = [&](auto&& f) {
        for (uint32_t c = 0; c < cluster_count(); ++c) {
            for (uint32_t id : members(c)) {
                const Triangle& t = triangles[id];
                for (int corner = 0; corner < 3; ++corner) {
                    const uint32_t v = t[corner];
                    if (last[v] == c) continue;
                    last[v] = c;
                    f(v, c);
                }
            }
        }
    };
    visit([&](uint32_t v, uint32_t) { ++m_vertex_offsets[v + 1]; });
    for (std::size_t v = 0; v < vertices; ++v) m_vertex_offsets[v + 1] += m_vertex_offsets[v];
    m_vertex_clusters.resize(m_vertex_offsets[vertices]);
    std::fill(last.begin(), last.end(), UINT32_MAX);
    std::vector<uint32_t> cursor(m_vertex_offsets.begin(), m_vertex_offsets.end() - 1);
    visit([&](uint32_t v, uint32_t c) { m_vertex_clusters[cursor[v]++] = c; });
    m_extra.clear();
}

void ClusterLayout::cut(const std::vector<uint64_t>& keys, uint32_t max_size) {
    // Step: split the sorted run at the highest Morton bit that differs inside it (the two
    // halves are the two children of the smallest cell holding it), down to max_size.
    std::vector<uint32_t> cuts;
    std::vector<std::pair<std::size_t, std::size_t>> stack{{0, keys.size()}};
    while (!stack.empty()) {
        const auto [begin, end] = stack.back();
        stack.pop_back();
        if (end - begin <= max_size) {
            cuts.push_back(static_cast<uint32_t>(begin));
            continue;
        }
        const uint32_t a = uint32_t(keys[begin] >> 32), b = uint32_t(keys[end - 1] >> 32);
        std::size_t mid = begin + (end - begin) / 2;  // one cell: halve it
        if (a != b) {
            const uint32_t bit = 31u - uint32_t(__builtin_clz(a ^ b));
            const uint32_t prefix = (b >> bit) << bit;  // codes >= prefix have the bit set
            mid = std::size_t(std::lower_bound(keys.begin() + std::ptrdiff_t(begin),
                                               keys.begin() + std::ptrdiff_t(end),
                                               uint64_t(prefix) << 32) -
                              keys.begin());
        }
        stack.push_back({mid, end});  // popped second: cuts come out in order
        stack.push_back({begin, mid});
    }
    // Step: merge neighbouring pieces (siblings in the Morton order) while they fit.
    m_first.clear();
    for (std::size_t i = 0; i < cuts.size(); ++i) {
        const std::size_t end = i + 1 < cuts.size() ? cuts[i + 1] : keys.size();
        if (!m_first.empty() && end - m_first.back() <= max_size) continue;
        m_first.push_back(cuts[i]);
    }
    m_first.push_back(static_cast<uint32_t>(keys.size()));
}

std::vector<uint32_t> ClusterLayout::touched(const VertexRanges& ranges) const {
    std::vector<uint32_t> out;
    const auto vertices = static_cast<uint32_t>(m_vertex_offsets.size() - 1);
    if (ranges.count() >= vertices) {
        // Every vertex: every cluster (an unreferenced vertex belongs to none, but a mesh
        // rewritten whole is refit whole anyway).
        out.resize(cluster_count());
        for (uint32_t c = 0; c < cluster_count(); ++c) out[c] = c;
        return out;
    }
    std::vector<uint8_t> seen(cluster_count(), 0);
    for (const VertexRanges::Range& r : ranges.ranges()) {
        const uint32_t end = std::min(r.end, vertices);
        for (uint32_t v = r.begin; v < end; ++v) {
            for_each_cluster_of(v, [&](uint32_t c) {
                if (seen[c]) return;
                seen[c] = 1;
                out.push_back(c);
            });
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<uint32_t> ClusterLayout::holding(const TriangleSplices& splices) const {
    // A bit per triangle of the last commit, set where a run replaced it: one cheap test per
    // cluster member.
    std::vector<uint64_t> replaced((std::size_t(m_triangle_count) + 63) / 64, 0);
    for (const TriangleSplices::Run& run : splices.runs())
        for (uint32_t t = run.old_first; t < std::min(run.old_end, m_triangle_count); ++t)
            replaced[t >> 6] |= uint64_t(1) << (t & 63);
    std::vector<uint8_t> holds(cluster_count(), 0);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cluster_count(), 16),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t c = r.begin(); c != r.end(); ++c) {
                              for (uint32_t id : members(c)) {
                                  if (replaced[id >> 6] >> (id & 63) & 1) {
                                      holds[c] = 1;
                                      break;
                                  }
                              }
                          }
                      });
    std::vector<uint32_t> out;
    for (uint32_t c = 0; c < cluster_count(); ++c)
        if (holds[c]) out.push_back(c);
    return out;
}

void ClusterLayout::splice(const TriangleRenumbering& renumber, std::span<const uint32_t> clusters,
                           std::vector<std::vector<uint32_t>>&& members,
                           std::span<const Triangle> triangles, std::size_t vertex_count) {
    // Step: the re-made clusters take their new members.
    std::vector<uint8_t> remade(cluster_count(), 0);
    for (std::size_t i = 0; i < clusters.size(); ++i) {
        const uint32_t c = clusters[i];
        remade[c] = 1;
        m_remade[c] = 1;
        m_own[c] = std::move(members[i]);
        m_ids[c] = m_own[c].data();
        m_size[c] = static_cast<uint32_t>(m_own[c].size());
    }
    m_triangle_count = static_cast<uint32_t>(triangles.size());

    // Step: the other clusters' triangles are renumbered (none of them was replaced).
    if (renumber.moves()) {
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cluster_count(), 16),
                          [&](const tbb::blocked_range<uint32_t>& r) {
                              for (uint32_t c = r.begin(); c != r.end(); ++c) {
                                  if (remade[c]) continue;
                                  uint32_t* ids = m_ids[c];
                                  for (uint32_t k = 0; k < m_size[c]; ++k)
                                      ids[k] = renumber(ids[k]).value_or(ids[k]);
                              }
                          });
    }

    // Step: the vertices the re-made clusters use. Past a quarter of the map, it is built anew.
    std::vector<uint64_t> added;
    for (uint32_t c : clusters) {
        for (uint32_t id : this->members(c)) {
            const Triangle& t = triangles[id];
            for (int corner = 0; corner < 3; ++corner)
                added.push_back(uint64_t(t[corner]) << 32 | c);
        }
    }
    if (m_extra.size() + added.size() > m_vertex_clusters.size() / 4 + 1024) {
        map_vertices(triangles, vertex_count);
        return;
    }
    std::sort(added.begin(), added.end());
    const std::size_t mid = m_extra.size();
    m_extra.insert(m_extra.end(), added.begin(), added.end());
    std::inplace_merge(m_extra.begin(), m_extra.begin() + std::ptrdiff_t(mid), m_extra.end());
    m_extra.erase(std::unique(m_extra.begin(), m_extra.end()), m_extra.end());
}

void ClusterLayout::write_sorted(std::span<const Triangle> triangles, Triangle* out) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m_order.size(), 65536),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k != r.end(); ++k)
                              out[k] = triangles[m_order[k]];
                      });
}

ClusterMetrics ClusterLayout::measure(std::span<const Vec3> positions, const Triangle* tris,
                                      uint32_t count) {
    ClusterMetrics m;
    for (uint32_t k = 0; k < count; ++k) measure_into(m, positions, tris[k]);
    return m;
}

}  // namespace strata

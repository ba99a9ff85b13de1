#include "engine/accel/blas_pool.h"

#include <algorithm>
#include <cstring>

#include <embree3/rtcore.h>

#include "engine/accel/embree_device.h"
#include "engine/core/hash.h"
#include "engine/scene/scene.h"

namespace strata {

namespace {

/// Words of a sample of the mesh: this many vertices and triangles spread over it.
constexpr std::size_t SAMPLES = 64;

uint32_t word(float f) {
    uint32_t w;
    std::memcpy(&w, &f, sizeof w);
    return w;
}

/// Whether `blas`'s Embree buffers hold exactly `mesh`'s positions and triangles.
bool same_content(const SharedBlas& blas, const MeshRecord& mesh) {
    if (blas.vertex_count != mesh.positions.size() ||
        blas.triangle_count != mesh.triangles.size())
        return false;
    const void* v = rtcGetGeometryBufferData(blas.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    const void* t = rtcGetGeometryBufferData(blas.geometry, RTC_BUFFER_TYPE_INDEX, 0);
    return v && t &&
           std::memcmp(v, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3)) == 0 &&
           std::memcmp(t, mesh.triangles.data(), mesh.triangles.size() * sizeof(Triangle)) == 0;
}

}  // namespace

uint64_t shared_blas_key(const MeshRecord& mesh, int scene_flags) {
    const std::vector<Vec3>& p = mesh.positions;
    const std::vector<Triangle>& t = mesh.triangles;
    uint32_t a = hash_combine(uint32_t(p.size()), uint32_t(t.size()));
    uint32_t b = hash_combine(uint32_t(scene_flags), uint32_t(mesh.build.prefer));
    b = hash_combine(b, uint32_t(mesh.build.allow_refit) | uint32_t(mesh.build.compact) << 1);
    for (std::size_t i = 0; i < SAMPLES && !p.empty(); ++i) {
        const Vec3& v = p[i * p.size() / SAMPLES];
        a = hash_combine(hash_combine(hash_combine(a, word(v.x)), word(v.y)), word(v.z));
    }
    for (std::size_t i = 0; i < SAMPLES && !t.empty(); ++i) {
        const Triangle& tri = t[i * t.size() / SAMPLES];
        b = hash_combine(hash_combine(hash_combine(b, tri.x), tri.y), tri.z);
    }
    return uint64_t(a) << 32 | b;
}

std::shared_ptr<SharedBlas> BlasPool::hold(const MeshRecord& mesh, int scene_flags,
                                           uint64_t key, EmbreeDevice& view) {
    std::lock_guard lock(m_mutex);
    const auto [begin, end] = m_by_key.equal_range(key);
    for (auto it = begin; it != end; ++it) {
        SharedBlas& b = *it->second;
        const bool held = std::find(b.holders.begin(), b.holders.end(), &view) != b.holders.end();
        if (held || b.scene_flags != scene_flags || !(b.options == mesh.build) ||
            !same_content(b, mesh))
            continue;
        b.holders.push_back(&view);
        b.held_by_others = true;
        return it->second;
    }
    return nullptr;
}

void BlasPool::publish(const std::shared_ptr<SharedBlas>& blas) {
    std::lock_guard lock(m_mutex);
    m_by_key.emplace(blas->key, blas);
}

void BlasPool::erase(const SharedBlas& blas) {
    const auto [begin, end] = m_by_key.equal_range(blas.key);
    for (auto it = begin; it != end; ++it) {
        if (it->second.get() != &blas) continue;
        m_by_key.erase(it);
        return;
    }
}

int64_t BlasPool::release(const std::shared_ptr<SharedBlas>& blas, EmbreeDevice& view) {
    std::lock_guard lock(m_mutex);
    SharedBlas& b = *blas;
    const auto it = std::find(b.holders.begin(), b.holders.end(), &view);
    if (it != b.holders.end()) b.holders.erase(it);
    if (b.holders.empty()) {
        erase(b);
        return b.owner == &view ? b.bytes : 0;
    }
    if (b.owner == &view) {
        view.transfer_to(*b.holders.front(), MemoryCategory::Blas, b.bytes);
        b.owner = b.holders.front();
    }
    return 0;
}

int64_t BlasPool::bytes_for(const SharedBlas& blas, const EmbreeDevice& view) const {
    std::lock_guard lock(m_mutex);
    return blas.owner == &view ? blas.bytes : 0;
}

bool BlasPool::frozen(const SharedBlas& blas, const EmbreeDevice& view) const {
    std::lock_guard lock(m_mutex);
    return blas.held_by_others ||
           std::any_of(blas.holders.begin(), blas.holders.end(),
                       [&](const EmbreeDevice* h) { return h != &view; });
}

bool BlasPool::withdraw(const std::shared_ptr<SharedBlas>& blas, const EmbreeDevice& view) {
    std::lock_guard lock(m_mutex);
    const bool alone = std::all_of(blas->holders.begin(), blas->holders.end(),
                                   [&](const EmbreeDevice* h) { return h == &view; });
    if (!alone || blas->held_by_others) return false;
    erase(*blas);
    return true;
}

std::size_t BlasPool::size() const {
    std::lock_guard lock(m_mutex);
    return m_by_key.size();
}

SharedBlasStats BlasPool::stats() const {
    std::lock_guard lock(m_mutex);
    SharedBlasStats out;
    for (const auto& [key, blas] : m_by_key) {
        ++out.count;
        out.holds += blas->holders.size() - 1;
        out.bytes += uint64_t(std::max<int64_t>(blas->bytes, 0));
    }
    return out;
}

}  // namespace strata

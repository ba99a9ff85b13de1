#include "engine/accel/tlas.h"

#include "engine/accel/blas_store.h"
#include "engine/accel/lod_scenes.h"
#include "engine/scene/scene.h"

namespace strata {

const char* tlas_kind_name(TlasKind k) {
    return k == TlasKind::Embree ? "embree" : "incremental";
}

std::optional<TlasKind> parse_tlas_kind(std::string_view name) {
    if (name == "incremental") return TlasKind::Incremental;
    if (name == "embree") return TlasKind::Embree;
    return std::nullopt;
}

}  // namespace strata

namespace strata {

TlasStrategy::TlasStrategy() = default;
TlasStrategy::~TlasStrategy() = default;

RTCSceneTy* TlasStrategy::instanced_scene(EmbreeDevice& device, const BlasStore& blas,
                                          uint32_t slot, const InstanceRecord& r) {
    note_blas(blas, slot, r.mesh.index);
    if (!m_lod) {
        if (r.rare->world_lod.empty()) return blas.scene(r.mesh.index);
        m_lod = std::make_unique<LodScenes>(device);
    }
    return m_lod->instanced_scene(blas, slot, r);
}

void TlasStrategy::sweep_lod(const BlasStore& blas) {
    if (m_lod) m_lod->sweep(blas);
}

bool TlasStrategy::blas_clustered() const { return m_blas->any_clustered(); }

uint32_t TlasStrategy::mesh_triangle(uint32_t slot, uint32_t geom, uint32_t prim) const {
    if (!m_blas || !m_blas->any_clustered() || slot >= m_instance_mesh.size()) return prim;
    return m_blas->mesh_triangle(m_instance_mesh[slot], geom, prim);
}

void TlasStrategy::to_mesh_triangles(RayHit1& ray) const {
    if (ray.inst_id == INVALID_ID) return;
    ray.prim_id = m_blas->mesh_triangle(m_instance_mesh[ray.inst_id], ray.geom_id, ray.prim_id);
    ray.geom_id = 0;
}

void TlasStrategy::to_mesh_triangles(const ValidMask16& valid, RayHit16& rays) const {
    for (uint32_t i = 0; i < 16; ++i) {
        if (!valid.lanes[i] || rays.inst_id[i] == INVALID_ID) continue;
        rays.prim_id[i] =
            m_blas->mesh_triangle(m_instance_mesh[rays.inst_id[i]], rays.geom_id[i], rays.prim_id[i]);
        rays.geom_id[i] = 0;
    }
}

}  // namespace strata

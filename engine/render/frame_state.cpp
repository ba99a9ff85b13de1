#include "engine/render/frame_state.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "engine/render/tangents.h"

namespace strata {

namespace {

/// The mean colour of a texture's texels (what the light table gives a textured emitter).
Vec3 mean_color(const TextureImage& t) {
    glm::dvec3 sum(0.0);
    const std::size_t n = std::size_t(t.width) * t.height;
    for (std::size_t i = 0; i < n; ++i)
        sum += glm::dvec3(t.texels[i * 3], t.texels[i * 3 + 1], t.texels[i * 3 + 2]);
    return n > 0 ? Vec3(sum / (double(n) * 65535.0)) : Vec3(1.0f);
}

/// HitTest::keep over a FrameState: mask cuts below the cutoff, blend keeps a hit with
/// probability equal to its coverage (drawn from the ray's seed).
bool keep_covered(const void* user, uint32_t slot, uint32_t prim, float u, float v,
                  uint32_t seed) {
    const auto& f = *static_cast<const FrameState*>(user);
    if (slot >= f.instances.size()) return true;
    const InstanceShade& inst = f.instances[slot];
    const Material& m = f.materials[inst.material];
    if (m.alpha_mode == AlphaMode::Opaque) return true;
    const float a = f.coverage(inst.material, f.mesh_shade(inst.mesh_slot), prim, u, v);
    if (m.alpha_mode == AlphaMode::Mask) return a >= m.alpha_cutoff;
    return float(seed >> 8) * (1.0f / 16777216.0f) < a;
}

/// (slot, names[slot]) for every distinct slot in `ids` but MISS_ID, sorted by slot.
std::vector<std::pair<uint32_t, std::string>> named_slots(const std::vector<uint32_t>& ids,
                                                          const std::vector<std::string>& names) {
    std::vector<bool> seen(names.size(), false);
    std::vector<std::pair<uint32_t, std::string>> out;
    for (uint32_t id : ids) {
        if (id == MISS_ID || id >= seen.size() || seen[id]) continue;
        seen[id] = true;
    }
    for (uint32_t slot = 0; slot < seen.size(); ++slot) {
        if (seen[slot]) out.emplace_back(slot, names[slot]);
    }
    return out;
}

}  // namespace

FrameIdNames FrameState::id_names(const FrameBuffers& buffers) const {
    FrameIdNames out;
    if (buffers.aovs.has(Aov::InstanceId))
        out.instances = named_slots(buffers.instance_id, instance_ids);
    if (buffers.aovs.has(Aov::MeshId)) out.meshes = named_slots(buffers.mesh_id, mesh_ids);
    return out;
}

SurfaceMaterial FrameState::surface(uint32_t material, const MeshShade* mesh, uint32_t prim,
                                    float u, float v) const {
    SurfaceMaterial s{materials[material]};
    const MaterialTextures& tex = material_textures[material];
    if (!mesh || prim >= mesh->triangles.size()) return s;
    const TextureSampler& sampler = s.material.base_color_sampler;
    Material& m = s.material;
    // Each slot's texture at its own coordinate set (each set interpolated once); none without
    // a texture or coordinates.
    Vec3 texel;
    std::optional<Vec2> at[2];
    const auto read = [&](TextureSlot slot) {
        const TextureImage* t = tex[slot_index(slot)].get();
        const std::vector<Vec2>* set =
            t ? mesh->uv_set(m.*(TEXTURE_SLOTS[slot_index(slot)].uv_set)) : nullptr;
        if (!set) return false;
        std::optional<Vec2>& uv = at[set == &mesh->uvs ? 0 : 1];
        if (!uv) uv = mesh->uv(*set, prim, u, v);
        texel = t->sample(*uv, sampler);
        return true;
    };
    if (read(TextureSlot::BaseColor)) m.base_color *= texel;
    if (read(TextureSlot::MetallicRoughness)) {
        m.roughness *= texel.y;
        m.metallic *= texel.z;
    }
    if (read(TextureSlot::Emissive)) m.emission *= texel;
    if (read(TextureSlot::Occlusion)) s.occlusion = 1.0f + m.occlusion_strength * (texel.x - 1.0f);
    if (!mesh->tangents.empty() && read(TextureSlot::Normal)) {
        const Vec3 c = texel * 2.0f - Vec3(1.0f);
        s.tangent_normal = Vec3(c.x * m.normal_scale, c.y * m.normal_scale, c.z);
        s.normal_mapped = true;
    }
    return s;
}

float FrameState::coverage(uint32_t material, const MeshShade* mesh, uint32_t prim, float u,
                           float v) const {
    const Material& m = materials[material];
    const TextureImage* t = material_textures[material][slot_index(TextureSlot::BaseColor)].get();
    if (!t || !mesh || prim >= mesh->triangles.size()) return m.alpha;
    const std::vector<Vec2>* set = mesh->uv_set(m.base_color_uv_set);
    if (!set) return m.alpha;
    return m.alpha * t->sample_alpha(mesh->uv(*set, prim, u, v), m.base_color_sampler);
}

std::optional<HitTest> FrameState::hit_test() const {
    if (m_see_through == 0) return std::nullopt;
    return HitTest{keep_covered, this};
}

void FrameState::refresh_material(const Scene& scene, MaterialHandle h) {
    const std::size_t i = h.index + 1;
    if (i >= materials.size()) {
        materials.resize(i + 1);
        material_textures.resize(i + 1);
        emitter_emission.resize(i + 1, Vec3(0.0f));
    }
    m_see_through -= materials[i].alpha_mode != AlphaMode::Opaque;
    if (const MaterialRecord* m = scene.materials().get(h)) {
        materials[i] = m->material;
        // Launches copy a hit's material: a long name would cost an allocation per hit.
        materials[i].name.clear();
        for (std::size_t s = 0; s < TEXTURE_SLOT_COUNT; ++s) {
            const TextureRecord* t = scene.textures().get(m->textures[s]);
            material_textures[i][s] = t ? t->image : nullptr;
        }
    } else if (!scene.materials().alive_at(h.index)) {
        materials[i] = Material{};
        material_textures[i] = {};  // removed: let its texels go
    }
    m_see_through += materials[i].alpha_mode != AlphaMode::Opaque;
    const TextureImage* emissive = material_textures[i][slot_index(TextureSlot::Emissive)].get();
    emitter_emission[i] = materials[i].emission;
    if (emissive && glm::any(glm::greaterThan(materials[i].emission, Vec3(0.0f))))
        emitter_emission[i] *= mean_color(*emissive);
}

bool FrameState::emits(const Scene& scene, uint32_t slot) const {
    if (!scene.instances().alive_at(slot) || !scene.instances().at_slot(slot).world_visible)
        return false;
    // Only triangles are sampled as lights; emitting points and curves are found by bounces, and
    // so are the levels of LOD groups (the table is made here, before a launch's camera chooses
    // which level is drawn).
    if (!scene.instances().at_slot(slot).rare->world_lod.empty()) return false;
    const MeshRecord* mesh = scene.meshes().get(scene.instances().at_slot(slot).mesh);
    if (!mesh || mesh->kind != MeshKind::Triangles) return false;
    const Vec3& e = materials[instances[slot].material].emission;
    return e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
}

FrameState::EmitterChange FrameState::refresh_instance(const Scene& scene, uint32_t slot) {
    InstanceShade& shade = instances[slot];
    const bool was = m_emitter[slot] != 0;
    if (!scene.instances().alive_at(slot)) {
        shade = InstanceShade{};
        instance_ids[slot].clear();
        m_emitter[slot] = 0;
        return {-int64_t(was), was};
    }
    const InstanceRecord& r = scene.instances().at_slot(slot);
    instance_ids[slot] = r.id;
    MaterialHandle material = r.material;
    if (!scene.materials().contains(material)) material = scene.meshes().get(r.mesh)->material;
    shade.material = scene.materials().contains(material) ? material.index + 1 : DEFAULT_MATERIAL;
    shade.mesh_slot = r.mesh.index;
    shade.user_id = r.user_id;
    shade.normal_matrix = r.world.normal_matrix();
    if (r.rare->world_motion.empty())
        shade.motion = {};
    else
        shade.motion.mut() = {r.rare->world_motion, r.rare->world_interpolation};
    const bool now = emits(scene, slot);
    m_emitter[slot] = now;
    return {int64_t(now) - int64_t(was), was || now};
}

bool FrameState::refresh_instances(const Scene& scene, std::span<const InstanceHandle> handles) {
    // Step: the tables grow to the highest slot listed.
    uint32_t end = uint32_t(instances.size());
    bool ascending = true;  // then no slot is listed twice (a slot reused within one batch is)
    for (std::size_t i = 0; i < handles.size(); ++i) {
        end = std::max(end, handles[i].index + 1);
        ascending = ascending && (i == 0 || handles[i - 1].index < handles[i].index);
    }
    if (end > instances.size()) {
        instances.resize(end);
        instance_ids.resize(end);
        m_emitter.resize(end, 0);
    }
    // Step: each slot's own entries, in parallel for the many a bulk edit or first build lists.
    auto refresh = [&](std::size_t begin, std::size_t stop) {
        EmitterChange sum;
        for (std::size_t i = begin; i < stop; ++i)
            sum = sum + refresh_instance(scene, handles[i].index);
        return sum;
    };
    constexpr std::size_t PARALLEL_FROM = 4096;
    const EmitterChange total =
        !ascending || handles.size() < PARALLEL_FROM
            ? refresh(0, handles.size())
            : tbb::parallel_reduce(
                  tbb::blocked_range<std::size_t>(0, handles.size(), 1024), EmitterChange{},
                  [&](const tbb::blocked_range<std::size_t>& r, const EmitterChange& sum) {
                      return sum + refresh(r.begin(), r.end());
                  },
                  std::plus<>());
    m_emitters = std::size_t(int64_t(m_emitters) + total.count);
    return total.touched;
}

void FrameState::rebuild_lights(const Scene& scene) {
    std::vector<Light> list;
    list.reserve(scene.lights().size());
    scene.lights().for_each([&](LightHandle, const LightRecord& r) { list.push_back(r.light); });
    std::vector<EmitterTriangle> emitters;
    for (uint32_t slot = 0; m_emitters > 0 && slot < m_emitter.size(); ++slot) {
        if (!m_emitter[slot]) continue;
        const InstanceRecord& inst = scene.instances().at_slot(slot);
        const MeshRecord& mesh = scene.meshes().at(inst.mesh);
        const Vec3 emission = emitter_emission[instances[slot].material];
        for (const Triangle& t : mesh.triangles) {
            const Vec3 a = inst.world.transform_point(mesh.positions[t[0]]);
            const Vec3 e1 = inst.world.transform_point(mesh.positions[t[1]]) - a;
            const Vec3 e2 = inst.world.transform_point(mesh.positions[t[2]]) - a;
            const float area = 0.5f * glm::length(glm::cross(e1, e2));
            if (area > 0.0f && std::isfinite(area)) emitters.push_back({a, e1, e2, emission, area});
        }
    }
    lights.build(std::move(list), std::move(emitters));
}

void FrameState::refresh_mesh(const Scene& scene, MeshHandle h) {
    if (h.index >= mesh_ids.size()) mesh_ids.resize(h.index + 1);
    mesh_ids[h.index] = scene.meshes().alive_at(h.index) ? scene.meshes().at_slot(h.index).id : "";
    const MeshRecord* r = scene.meshes().get(h);
    if (!r) {
        // Removed: clear the slot unless a newer mesh already lives there.
        if (h.index < meshes.size() && !scene.meshes().alive_at(h.index)) meshes[h.index].reset();
        return;
    }
    if (!r->dirty.bits.has(MeshDirty::Added | MeshDirty::Topology | MeshDirty::Triangles |
                           MeshDirty::Attributes))
        return;
    if (h.index >= meshes.size()) meshes.resize(h.index + 1);
    if (r->normals.empty() && r->uvs.empty() && r->uvs1.empty()) {
        meshes[h.index].reset();
        return;
    }
    auto shade =
        std::make_shared<MeshShade>(MeshShade{r->triangles, r->normals, r->uvs, r->uvs1, {}});
    // The mesh's own tangents (a file's), else made in MikkTSpace's convention.
    if (!r->normals.empty() && !r->uvs.empty())
        shade->tangents = r->tangents.empty()
                              ? make_tangents(r->positions, r->triangles, r->normals, r->uvs)
                              : r->tangents;
    meshes[h.index] = std::move(shade);
}

void FrameState::sync(const Scene& scene) {
    const ChangeTracker& changes = scene.changes();
    version = scene.version();
    if (changes.has(SceneDirty::Camera)) camera = scene.camera();
    if (changes.has(SceneDirty::Lighting)) lighting = scene.lighting();
    // Emitters: an emissive material changed (every instance may have gained or lost one), an
    // instance that is or was an emitter changed, or the mesh of one did.
    bool rescan = false;
    for (MaterialHandle h : changes.materials()) {
        const Material before =
            h.index + 1 < materials.size() ? materials[h.index + 1] : Material{};
        refresh_material(scene, h);
        const Material& after = materials[h.index + 1];
        rescan = rescan || glm::any(glm::greaterThan(before.emission, Vec3(0.0f))) ||
                 glm::any(glm::greaterThan(after.emission, Vec3(0.0f)));
    }
    for (MeshHandle h : changes.meshes()) refresh_mesh(scene, h);
    bool emitters_changed = refresh_instances(scene, changes.instances());
    if (rescan) {
        // A material's emission changed: which instances emit is read again (O(instances), and
        // only for such edits).
        m_emitters = 0;
        for (uint32_t slot = 0; slot < m_emitter.size(); ++slot) {
            m_emitter[slot] = emits(scene, slot);
            m_emitters += m_emitter[slot];
        }
        emitters_changed = true;
    }
    for (MeshHandle h : changes.meshes()) {
        const MeshRecord* r = scene.meshes().get(h);
        if (!r || m_emitters == 0 || !r->dirty.bits.has(MeshDirty::Points | MeshDirty::Topology |
                                                          MeshDirty::Triangles))
            continue;
        for (InstanceHandle user : r->users) emitters_changed = emitters_changed || is_emitter(user.index);
    }
    if (emitters_changed || changes.has(SceneDirty::Lights)) rebuild_lights(scene);
}

}  // namespace strata

#include "tests/engine/random_edits.h"

#include <algorithm>
#include <cmath>

#include "engine/scene/shapes.h"

namespace strata::test {

std::string RandomEdits::fresh(const char* prefix) {
    // Ids are sometimes reused after removal, which re-adds an object under an old name.
    return std::string(prefix) + std::to_string(m_counter++ % 40);
}

std::string RandomEdits::pick(const std::vector<std::string>& v) {
    return v[std::size_t(integer(0, int(v.size()) - 1))];
}

std::vector<std::string> RandomEdits::mesh_ids() const {
    std::vector<std::string> out;
    for (const auto& [id, info] : m_meshes) out.push_back(id);
    return out;
}

std::vector<std::string> RandomEdits::instance_ids() const {
    std::vector<std::string> out;
    for (const auto& [id, mesh] : m_instances) out.push_back(id);
    return out;
}

uint32_t RandomEdits::ray_mask() { return chance(0.8) ? 0xFFFFFFFFu : 0x1u; }

void RandomEdits::random_points(AddMesh& e) {
    e.kind = MeshKind::Points;
    for (int i = integer(3, 60); i > 0; --i) {
        e.positions.emplace_back(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
        e.radii.push_back(uniform(0.05f, 0.3f));
    }
}

void RandomEdits::random_curves(AddMesh& e, CurveBasis basis) {
    e.kind = MeshKind::Curves;
    e.basis = basis;
    for (int s = integer(1, 5); s > 0; --s) {
        const int n = basis == CurveBasis::Linear   ? integer(2, 6)
                      : basis == CurveBasis::Bezier ? 3 * integer(1, 3) + 1
                                                    : integer(4, 8);
        e.strands.push_back(uint32_t(n));
        Vec3 p(uniform(-1, 1), uniform(-1, 0), uniform(-1, 1));
        for (int k = 0; k < n; ++k) {
            e.positions.push_back(p);
            e.radii.push_back(uniform(0.03f, 0.15f));
            p += Vec3(uniform(-0.3f, 0.3f), uniform(0.1f, 0.4f), uniform(-0.3f, 0.3f));
        }
    }
}

std::vector<Vec3> RandomEdits::random_keys(const std::vector<Vec3>& around, uint32_t k) {
    std::vector<Vec3> keys;
    keys.reserve(around.size() * k);
    for (const Vec3& p : around)
        for (uint32_t j = 1; j <= k; ++j)
            keys.push_back(p + float(j) * Vec3(uniform(-0.1f, 0.1f), uniform(-0.1f, 0.1f),
                                               uniform(-0.1f, 0.1f)));
    return keys;
}

void RandomEdits::maybe_keys(AddMesh& e) {
    if (chance(0.2)) e.motion_positions = random_keys(e.positions, uint32_t(integer(1, 3)));
}

AddMesh RandomEdits::random_mesh(const std::string& id) {
    MeshData data;
    if (chance(0.25)) {
        AddMesh e;
        e.id = id;
        if (chance(0.5)) {
            random_points(e);
        } else {
            random_curves(e, CurveBasis(integer(0, 3)));
            e.style = chance(0.3) ? CurveStyle::Flat : CurveStyle::Round;
        }
        e.build.allow_refit = chance(0.75);
        e.build.compact = chance(0.25);
        if (!m_materials.empty() && chance(0.5)) e.material = pick(m_materials);
        maybe_keys(e);
        m_positions[id] = e.positions;
        return e;
    }
    switch (integer(0, 2)) {
        case 0: data = make_sphere(uniform(0.4f, 1.2f), uint32_t(integer(5, 18))); break;
        case 1: data = make_box({uniform(0.3f, 1.5f), uniform(0.3f, 1.5f), uniform(0.3f, 1.5f)}); break;
        default:
            data = make_plane({uniform(0.5f, 2.5f), 0.0f, uniform(0.5f, 2.5f)}, uint32_t(integer(1, 6)),
                              uint32_t(integer(1, 6)));
            break;
    }
    // Jitter every vertex so no two surfaces are exactly coplanar or axis-aligned with rays.
    for (Vec3& p : data.positions) p += Vec3(uniform(-0.02f, 0.02f), uniform(-0.02f, 0.02f), uniform(-0.02f, 0.02f));
    AddMesh e;
    e.id = id;
    e.positions = data.positions;
    e.triangles = std::move(data.triangles);
    e.build.prefer = chance(0.5) ? BuildPreference::FastTrace : BuildPreference::FastBuild;
    e.build.allow_refit = chance(0.75);
    e.build.compact = chance(0.25);
    if (!m_materials.empty() && chance(0.5)) e.material = pick(m_materials);
    maybe_keys(e);
    m_positions[id] = std::move(data.positions);
    return e;
}

ReplaceMeshTopology RandomEdits::random_topology(const std::string& id) {
    const MeshInfo& info = m_meshes[id];
    AddMesh shape;
    if (info.kind == MeshKind::Points) {
        random_points(shape);
    } else if (info.kind == MeshKind::Curves) {
        random_curves(shape, info.basis);
    } else {
        do shape = random_mesh(id);
        while (shape.kind != MeshKind::Triangles);
    }
    m_positions[id] = shape.positions;
    ReplaceMeshTopology t;
    t.mesh = id;
    t.positions = std::move(shape.positions);
    t.triangles = std::move(shape.triangles);
    if (info.kind != MeshKind::Triangles) t.radii = std::move(shape.radii);
    if (info.kind == MeshKind::Curves) t.strands = std::move(shape.strands);
    // New vertex keys for the new vertices, or none (kept ones would not fit a new count).
    t.motion_positions = chance(0.3) ? random_keys(*t.positions, uint32_t(integer(1, 2)))
                                     : std::vector<Vec3>{};
    return t;
}

Affine RandomEdits::random_transform() {
    const Vec3 t(uniform(-4, 4), uniform(-3, 3), uniform(-4, 4));
    const Vec3 r(uniform(-180, 180), uniform(-180, 180), uniform(-180, 180));
    const float s = uniform(0.5f, 1.6f);
    return Affine::trs(t, Affine::rotation_euler_deg(r), Vec3(s, s * uniform(0.8f, 1.25f), s));
}

void RandomEdits::add_mesh(EditBatch& b) {
    std::string id = fresh("m");
    if (m_meshes.count(id)) id += "x" + std::to_string(m_counter);
    if (m_meshes.count(id)) return;
    AddMesh add = random_mesh(id);
    m_meshes[id] = MeshInfo{uint32_t(add.positions.size()), 0, add.kind, add.basis,
                            uint32_t(add.motion_positions.size() / add.positions.size())};
    b.edits.emplace_back(std::move(add));
}

void RandomEdits::add_instance(EditBatch& b, const std::vector<std::string>& meshes) {
    const std::string id = fresh("i");
    if (m_instances.count(id)) return;
    AddInstance add;
    add.id = id;
    add.mesh = pick(meshes);
    add.transform = random_transform();
    if (!m_materials.empty() && chance(0.4)) add.material = pick(m_materials);
    add.visible = chance(0.9);
    add.mask = chance(0.8) ? 0xFFFFFFFFu : (chance(0.5) ? 0x2u : 0x1u);
    add.user_id = uint32_t(integer(0, 1000));
    ++m_meshes[add.mesh].instances;
    m_instances[id] = add.mesh;
    b.edits.emplace_back(std::move(add));
}

EditBatch RandomEdits::initial_batch(int meshes, int instances) {
    EditBatch b;
    for (int i = 0; i < meshes; ++i) add_mesh(b);
    const std::vector<std::string> ids = mesh_ids();
    for (int i = 0; i < instances; ++i) add_instance(b, ids);
    return b;
}

UpdateInstance RandomEdits::random_update_instance(const std::vector<std::string>& instances) {
    UpdateInstance u;
    u.instance = pick(instances);
    if (chance(0.5)) u.transform = random_transform();
    if (chance(0.4)) u.visible = chance(0.7);
    if (chance(0.3)) u.mask = chance(0.7) ? 0xFFFFFFFFu : 0x2u;
    if (chance(0.3)) {
        u.material = (!m_materials.empty() && chance(0.7))
                         ? std::optional<std::string>(pick(m_materials))
                         : std::nullopt;
    }
    if (chance(0.2)) u.user_id = uint32_t(integer(0, 1000));
    if (chance(0.15)) {  // motion keys, or none
        u.motion.emplace();
        for (int k = chance(0.3) ? 0 : integer(2, 5); k > 0; --k)
            u.motion->push_back(random_transform());
        u.animation = std::vector<Keyframe>{};  // an instance has one or the other
    } else if (chance(0.12)) {  // keyframes at increasing times, or none
        u.animation.emplace();
        u.motion = std::vector<Affine>{};
        float t = uniform(-1, 1);
        for (int k = chance(0.2) ? 0 : integer(1, 4); k > 0; --k) {
            u.animation->push_back({t, random_transform()});
            t += uniform(0.1f, 2);
        }
        u.animation_loop = chance(0.5);
    }
    if (chance(0.1))
        u.motion_interpolation =
            chance(0.5) ? MotionInterpolation::Srt : MotionInterpolation::Linear;
    return u;
}

SetCamera RandomEdits::random_camera() {
    SetCamera c;
    const float a = uniform(0, 6.28f), h = uniform(-0.3f, 0.9f);
    c.eye = Vec3(9.0f * std::cos(a), 9.0f * h, 9.0f * std::sin(a));
    c.target = Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    c.fov_y_deg = uniform(30, 70);
    if (chance(0.4)) {  // launches trace at the shutter's opening
        c.shutter_open = uniform(0, 1);
        c.shutter_close = std::min(1.0f, *c.shutter_open + uniform(0, 0.5f));
    }
    return c;
}

void RandomEdits::add_edit(EditBatch& b) {
    auto& e = b.edits;
    const std::vector<std::string> meshes = mesh_ids();
    const std::vector<std::string> instances = instance_ids();
    const int kind = integer(0, 99);

    if (meshes.empty() || kind < 12) {
        add_mesh(b);
    } else if (kind < 34) {
        add_instance(b, meshes);
    } else if (kind < 44 && !instances.empty()) {  // set_transform
        e.emplace_back(SetTransform{pick(instances), random_transform()});
    } else if (kind < 50 && !instances.empty()) {
        e.emplace_back(random_update_instance(instances));
    } else if (kind < 55 && !instances.empty()) {  // remove_instance
        const std::string id = pick(instances);
        --m_meshes[m_instances[id]].instances;
        m_instances.erase(id);
        e.emplace_back(RemoveInstance{id});
    } else if (kind < 67) {  // update_mesh positions: a wobble, a big move, or a range
        const std::string id = pick(meshes);
        std::vector<Vec3>& pos = m_positions[id];
        const float amplitude = chance(0.7) ? 0.05f : 0.8f;
        UpdateMeshPositions u;
        u.mesh = id;
        const uint32_t n = uint32_t(pos.size());
        u.offset = chance(0.5) ? 0 : uint32_t(integer(0, int(n) - 1));
        const uint32_t count = u.offset == 0 && chance(0.5) ? n : uint32_t(integer(1, int(n - u.offset)));
        // Points and curves: new radii for the range too, sometimes alone.
        const bool radii = m_meshes[id].kind != MeshKind::Triangles && chance(0.5);
        const bool radii_alone = radii && chance(0.3);
        for (uint32_t i = u.offset; i < u.offset + count && !radii_alone; ++i) {
            pos[i] += Vec3(uniform(-amplitude, amplitude), uniform(-amplitude, amplitude), uniform(-amplitude, amplitude));
            u.positions.push_back(pos[i]);
        }
        if (radii) {
            u.radii.emplace();
            for (uint32_t i = 0; i < count; ++i) u.radii->push_back(uniform(0.03f, 0.3f));
        }
        // Vertex keys: new ones for the range, removed, or added whole.
        MeshInfo& info = m_meshes[id];
        if (info.keys > 0 && chance(0.4)) {
            u.motion_positions = random_keys(
                std::vector<Vec3>(pos.begin() + u.offset, pos.begin() + u.offset + count),
                info.keys);
        } else if (info.keys > 0 && chance(0.1)) {
            u.motion_positions = std::vector<Vec3>{};
            info.keys = 0;
        } else if (info.keys == 0 && u.offset == 0 && chance(0.1)) {
            info.keys = uint32_t(integer(1, 3));
            u.motion_positions = random_keys(pos, info.keys);
        }
        e.emplace_back(std::move(u));
    } else if (kind < 73) {  // topology change: a different shape under the same id
        const std::string id = pick(meshes);
        ReplaceMeshTopology t = random_topology(id);
        m_meshes[id].vertices = uint32_t(t.positions->size());
        m_meshes[id].keys = uint32_t(t.motion_positions->size() / t.positions->size());
        e.emplace_back(std::move(t));
    } else if (kind < 76) {  // remove_mesh, removing its instances first in the same batch
        const std::string id = pick(meshes);
        for (auto it = m_instances.begin(); it != m_instances.end();) {
            if (it->second == id) {
                e.emplace_back(RemoveInstance{it->first});
                it = m_instances.erase(it);
            } else {
                ++it;
            }
        }
        m_meshes.erase(id);
        m_positions.erase(id);
        e.emplace_back(RemoveMesh{id});
    } else if (kind < 82) {  // materials
        if (m_materials.empty() || chance(0.5)) {
            const std::string id = "mat" + std::to_string(m_materials.size());
            m_materials.push_back(id);
            e.emplace_back(AddMaterial{id, Material{colour(), uniform(0, 1), uniform(0, 1), Vec3(0.0f)}});
        } else {
            UpdateMaterial u;
            u.material = pick(m_materials);
            u.base_color = colour();
            e.emplace_back(std::move(u));
        }
    } else if (kind < 86) {  // replace_triangles: the first triangle by one to three others
        const std::string id = pick(meshes);
        if (m_meshes[id].kind != MeshKind::Triangles) return;
        const uint32_t n = m_meshes[id].vertices;
        ReplaceMeshTriangles t{id, 0, chance(0.8) ? 1u : 0u, {}};
        for (int k = integer(1, 3); k > 0; --k)
            t.triangles.emplace_back(integer(0, int(n) - 1), integer(0, int(n) - 1),
                                     integer(0, int(n) - 1));
        e.emplace_back(std::move(t));
    } else if (kind < 90) {  // mark_dirty on a mesh or the TLAS
        const DirtyAction action = chance(0.5) ? DirtyAction::Refit : DirtyAction::Rebuild;
        if (chance(0.7)) {
            e.emplace_back(MarkDirty{pick(meshes), action});
        } else {
            e.emplace_back(MarkDirty{std::nullopt, action});
        }
    } else if (kind < 95) {
        e.emplace_back(random_camera());
    } else if (kind < 97) {  // the scene's clock: animated instances move
        e.emplace_back(SetTime{uniform(-1, 6), chance(0.5) ? uniform(0, 0.5f) : 1.0f / 24.0f});
    } else if (kind < 99) {  // lighting
        SetLighting l;
        l.sun_direction = Vec3(uniform(-1, 1), uniform(0.1f, 1), uniform(-1, 1));
        l.sky_intensity = uniform(0, 1);
        e.emplace_back(l);
    } else {  // clear, then start again
        m_meshes.clear();
        m_instances.clear();
        m_materials.clear();
        m_positions.clear();
        e.emplace_back(Clear{});
    }
}

EditBatch RandomEdits::next_batch(int max_edits) {
    EditBatch b;
    const int n = integer(1, max_edits);
    while (int(b.edits.size()) < n) add_edit(b);
    return b;
}

}  // namespace strata::test

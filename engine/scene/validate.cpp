// Batch validation: every edit is checked against the scene as the earlier edits of the same batch
// would leave it, using a small overlay of what those edits create and remove. Nothing is applied
// until the whole batch passes, so an invalid edit anywhere leaves the scene untouched.

#include <cmath>
#include <optional>
#include <unordered_map>

#include "engine/scene/scene.h"

namespace strata {

namespace {

/// Largest mesh the engine accepts; beyond this Embree's 32-bit primitive ids run out of room.
constexpr std::size_t MAX_MESH_ELEMENTS = std::size_t(1) << 28;

struct MeshShadow {
    uint32_t vertex_count = 0;
    std::size_t users = 0;
};

/// The scene as seen part-way through a batch: ids touched by earlier edits shadow the scene.
class Overlay {
public:
    explicit Overlay(const Scene& s) : m_scene(s), m_camera(s.camera()), m_lighting(s.lighting()) {}

    std::optional<MeshShadow> mesh(const std::string& id) const {
        if (auto it = m_meshes.find(id); it != m_meshes.end()) return it->second;
        if (m_cleared) return std::nullopt;
        const auto r = m_scene.mesh(m_scene.find_mesh(id));
        if (!r) return std::nullopt;
        return MeshShadow{static_cast<uint32_t>(r.value()->positions.size()),
                          r.value()->users.size()};
    }
    /// The mesh id an instance refers to, if the instance exists.
    std::optional<std::string> instance(const std::string& id) const {
        if (auto it = m_instances.find(id); it != m_instances.end()) return it->second;
        if (m_cleared) return std::nullopt;
        const auto r = m_scene.instance(m_scene.find_instance(id));
        if (!r) return std::nullopt;
        return m_scene.mesh(r.value()->mesh).value()->id;
    }
    bool material(const std::string& id) const {
        if (auto it = m_materials.find(id); it != m_materials.end()) return it->second;
        return !m_cleared && !m_scene.find_material(id).is_null();
    }
    std::optional<Material> material_value(const std::string& id) const {
        if (auto it = m_material_values.find(id); it != m_material_values.end()) return it->second;
        if (!material(id)) return std::nullopt;
        return m_scene.material(m_scene.find_material(id)).value()->material;
    }

    void set_mesh(const std::string& id, std::optional<MeshShadow> m) { m_meshes[id] = m; }
    void set_instance(const std::string& id, std::optional<std::string> mesh) {
        m_instances[id] = std::move(mesh);
    }
    void set_material(const std::string& id, std::optional<Material> m) {
        m_materials[id] = m.has_value();
        m_material_values[id] = m;
    }
    void clear() {
        m_cleared = true;
        m_meshes.clear();
        m_instances.clear();
        m_materials.clear();
        m_material_values.clear();
        m_camera = Camera{};
        m_lighting = Lighting{};
    }

    Camera& camera() { return m_camera; }
    Lighting& lighting() { return m_lighting; }

private:
    const Scene& m_scene;
    bool m_cleared = false;
    std::unordered_map<std::string, std::optional<MeshShadow>> m_meshes;
    std::unordered_map<std::string, std::optional<std::string>> m_instances;
    std::unordered_map<std::string, bool> m_materials;
    std::unordered_map<std::string, std::optional<Material>> m_material_values;
    Camera m_camera;
    Lighting m_lighting;
};

Status fail(ErrorCode code, std::string message, std::string field = {}) {
    return failure(code, std::move(message), std::move(field));
}

Status check_new_id(const std::string& id, bool taken, const char* kind) {
    if (id.empty())
        return fail(ErrorCode::InvalidArgument, std::string(kind) + " id is empty", "id");
    if (taken)
        return fail(ErrorCode::DuplicateId, std::string(kind) + " '" + id + "' already exists",
                    "id");
    return {};
}

Status unknown(const char* kind, const std::string& id, const char* field) {
    return fail(ErrorCode::UnknownId, std::string("unknown ") + kind + " '" + id + "'", field);
}

/// `first_vertex` is the mesh vertex the array starts at (for messages); the field path indexes
/// the flat number array of the request.
Status check_positions(const std::vector<Vec3>& positions, const char* field,
                       uint64_t first_vertex = 0) {
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (is_finite(positions[i])) continue;
        const int k = std::isfinite(positions[i].x) ? (std::isfinite(positions[i].y) ? 2 : 1) : 0;
        return fail(ErrorCode::NotFinite,
                    "vertex " + std::to_string(first_vertex + i) + " has a NaN or infinite " +
                        "xyz"[k] + " coordinate",
                    std::string(field) + "/" + std::to_string(i * 3 + k));
    }
    return {};
}

Status check_triangles(const std::vector<Triangle>& tris, std::size_t vertex_count,
                       const char* field) {
    if (tris.size() > MAX_MESH_ELEMENTS)
        return fail(ErrorCode::TooLarge, "too many triangles (" + std::to_string(tris.size()) + ")",
                    field);
    for (std::size_t t = 0; t < tris.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            if (tris[t][k] >= vertex_count)
                return fail(ErrorCode::OutOfRange,
                            "triangle " + std::to_string(t) + " uses vertex " +
                                std::to_string(tris[t][k]) + " but the mesh has " +
                                std::to_string(vertex_count) + " vertices",
                            std::string(field) + "/" + std::to_string(t * 3 + k));
        }
    }
    return {};
}

Status check_transform(const Affine& t, const char* field) {
    if (const char* why = transform_problem(t)) {
        const bool finite = t.is_finite();
        return fail(finite ? ErrorCode::DegenerateTransform : ErrorCode::NotFinite, why, field);
    }
    return {};
}

Status check_material_ref(const Overlay& o, const std::optional<std::string>& id) {
    if (id && !o.material(*id)) return unknown("material", *id, "material");
    return {};
}

class Validator {
public:
    explicit Validator(const Scene& s) : m_overlay(s) {}

    Status check(const AddMesh& e) {
        if (Status s = check_new_id(e.id, m_overlay.mesh(e.id).has_value(), "mesh"); !s) return s;
        if (e.positions.empty() || e.triangles.empty())
            return fail(
                ErrorCode::EmptyMesh,
                "mesh '" + e.id + "' has no " + (e.positions.empty() ? "vertices" : "triangles"),
                e.positions.empty() ? "positions" : "indices");
        if (e.positions.size() > MAX_MESH_ELEMENTS)
            return fail(ErrorCode::TooLarge, "too many vertices", "positions");
        if (Status s = check_positions(e.positions, "positions"); !s) return s;
        if (Status s = check_triangles(e.triangles, e.positions.size(), "indices"); !s) return s;
        if (Status s = check_material_ref(m_overlay, e.material); !s) return s;
        m_overlay.set_mesh(e.id, MeshShadow{static_cast<uint32_t>(e.positions.size()), 0});
        return {};
    }

    Status check(const UpdateMeshPositions& e) {
        const auto m = m_overlay.mesh(e.mesh);
        if (!m) return unknown("mesh", e.mesh, "mesh");
        if (e.positions.empty())
            return fail(ErrorCode::InvalidArgument, "no positions given", "positions");
        const uint64_t end = uint64_t(e.offset) + e.positions.size();
        if (end > m->vertex_count)
            return fail(ErrorCode::OutOfRange,
                        "vertices [" + std::to_string(e.offset) + ", " + std::to_string(end) +
                            ") are outside mesh '" + e.mesh + "' which has " +
                            std::to_string(m->vertex_count) + " vertices",
                        e.offset ? "offset" : "positions");
        return check_positions(e.positions, "positions", e.offset);
    }

    Status check(const ReplaceMeshTopology& e) {
        auto m = m_overlay.mesh(e.mesh);
        if (!m) return unknown("mesh", e.mesh, "mesh");
        if (e.triangles.empty())
            return fail(ErrorCode::EmptyMesh, "mesh has no triangles", "indices");
        if (e.positions) {
            if (e.positions->empty())
                return fail(ErrorCode::EmptyMesh, "mesh has no vertices", "positions");
            if (e.positions->size() > MAX_MESH_ELEMENTS)
                return fail(ErrorCode::TooLarge, "too many vertices", "positions");
            if (Status s = check_positions(*e.positions, "positions"); !s) return s;
            m->vertex_count = static_cast<uint32_t>(e.positions->size());
        }
        if (Status s = check_triangles(e.triangles, m->vertex_count, "indices"); !s) return s;
        m_overlay.set_mesh(e.mesh, m);
        return {};
    }

    Status check(const RemoveMesh& e) {
        const auto m = m_overlay.mesh(e.mesh);
        if (!m) return unknown("mesh", e.mesh, "mesh");
        if (m->users > 0)
            return fail(ErrorCode::InUse,
                        "mesh '" + e.mesh + "' is still used by " + std::to_string(m->users) +
                            " instance(s)",
                        "mesh");
        m_overlay.set_mesh(e.mesh, std::nullopt);
        return {};
    }

    Status check(const AddMaterial& e) {
        if (Status s = check_new_id(e.id, m_overlay.material(e.id), "material"); !s) return s;
        if (Status s = check_material(e.material); !s) return s;
        m_overlay.set_material(e.id, e.material);
        return {};
    }

    Status check(const UpdateMaterial& e) {
        auto m = m_overlay.material_value(e.material);
        if (!m) return unknown("material", e.material, "material");
        apply_to(*m, e);
        if (Status s = check_material(*m); !s) return s;
        m_overlay.set_material(e.material, m);
        return {};
    }

    Status check(const AddInstance& e) {
        if (Status s = check_new_id(e.id, m_overlay.instance(e.id).has_value(), "instance"); !s)
            return s;
        auto m = m_overlay.mesh(e.mesh);
        if (!m) return unknown("mesh", e.mesh, "mesh");
        if (Status s = check_material_ref(m_overlay, e.material); !s) return s;
        if (Status s = check_transform(e.transform, "transform"); !s) return s;
        ++m->users;
        m_overlay.set_mesh(e.mesh, m);
        m_overlay.set_instance(e.id, e.mesh);
        return {};
    }

    Status check(const UpdateInstance& e) {
        if (!m_overlay.instance(e.instance)) return unknown("instance", e.instance, "instance");
        if (e.material) {
            if (Status s = check_material_ref(m_overlay, *e.material); !s) return s;
        }
        if (e.transform) {
            if (Status s = check_transform(*e.transform, "transform"); !s) return s;
        }
        return {};
    }

    Status check(const SetTransform& e) {
        if (!m_overlay.instance(e.instance)) return unknown("instance", e.instance, "instance");
        return check_transform(e.transform, "transform");
    }

    Status check(const RemoveInstance& e) {
        const auto mesh_id = m_overlay.instance(e.instance);
        if (!mesh_id) return unknown("instance", e.instance, "instance");
        auto m = m_overlay.mesh(*mesh_id);
        STRATA_CHECK(m && m->users > 0);
        --m->users;
        m_overlay.set_mesh(*mesh_id, m);
        m_overlay.set_instance(e.instance, std::nullopt);
        return {};
    }

    Status check(const MarkDirty& e) {
        if (e.mesh && !m_overlay.mesh(*e.mesh)) return unknown("mesh", *e.mesh, "target/mesh");
        return {};
    }

    Status check(const SetCamera& e) {
        apply_to(m_overlay.camera(), e);
        return check_camera(m_overlay.camera());
    }

    Status check(const SetLighting& e) {
        apply_to(m_overlay.lighting(), e);
        return check_lighting(m_overlay.lighting());
    }

    Status check(const Clear&) {
        m_overlay.clear();
        return {};
    }

private:
    Overlay m_overlay;
};

}  // namespace

Status Scene::validate(const EditBatch& batch) const {
    Validator v(*this);
    for (std::size_t i = 0; i < batch.edits.size(); ++i) {
        Status s = std::visit([&](const auto& e) { return v.check(e); }, batch.edits[i]);
        if (!s) {
            Error e = s.error();
            e.edit_index = i;
            return Unexpected(e);
        }
    }
    return {};
}

}  // namespace strata

#include "tests/engine/many_instances.h"

#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <string>

#include "engine/scene/shapes.h"

namespace strata::test {

namespace {
constexpr float SPACING = 1.6f;
}

Affine ManyInstances::placement(int cell) {
    const int side = int(std::ceil(std::sqrt(double(m_cells))));
    const float half = 0.5f * float(side) * SPACING;
    const Vec3 at(float(cell % side) * SPACING - half + uniform(-0.3f, 0.3f), uniform(-0.4f, 0.4f),
                  float(cell / side) * SPACING - half + uniform(-0.3f, 0.3f));
    const Vec3 r(uniform(-180, 180), uniform(-180, 180), uniform(-180, 180));
    const float s = uniform(0.5f, 0.9f);
    return Affine::trs(at, Affine::rotation_euler_deg(r), Vec3(s, s * uniform(0.8f, 1.2f), s));
}

EditBatch ManyInstances::initial_batch(int instances) {
    EditBatch b;
    m_cells = instances;
    const MeshData shapes[] = {make_sphere(0.6f, 8), make_sphere(0.5f, 12),
                               make_box({0.8f, 0.5f, 0.6f}), make_sphere(0.7f, 6)};
    for (int i = 0; i < 4; ++i) {
        MeshData data = shapes[i];
        for (Vec3& p : data.positions)
            p += Vec3(uniform(-0.01f, 0.01f), uniform(-0.01f, 0.01f), uniform(-0.01f, 0.01f));
        m_shapes.push_back(data.positions);
        const std::string id = "mesh" + std::to_string(i);
        BuildOptions build;
        build.allow_refit = i != 2;
        AddMesh add = add_mesh_edit(id, std::move(data), build);
        b.edits.emplace_back(std::move(add));
        m_meshes.push_back(id);
    }
    for (int i = 0; i < instances; ++i) {
        AddInstance add;
        add.id = "i" + std::to_string(m_next++);
        add.mesh = m_meshes[std::size_t(integer(0, 3))];
        add.transform = placement(i);
        add.mask = chance(0.8) ? 0xFFFFFFFFu : (chance(0.5) ? 0x1u : 0x2u);
        m_live.push_back({add.id, true});
        b.edits.emplace_back(std::move(add));
    }
    const int side = int(std::ceil(std::sqrt(double(m_cells))));
    SetCamera camera;
    camera.eye = Vec3(0.0f, 0.55f * float(side) * SPACING, -0.75f * float(side) * SPACING);
    camera.target = Vec3(0.0f, 0.0f, 0.05f * float(side) * SPACING);
    camera.fov_y_deg = 60.0f;
    b.edits.emplace_back(camera);
    return b;
}

EditBatch ManyInstances::moves(int count) {
    EditBatch b;
    for (int i = 0; i < count && !m_live.empty(); ++i) {
        const Live& l = m_live[std::size_t(integer(0, int(m_live.size()) - 1))];
        b.edits.emplace_back(SetTransform{l.id, random_placement()});
    }
    return b;
}

namespace {

/// Motion keys for edit `i` of instance `id` (rays see key 0's end of them at the default
/// shutter), none (an empty array) or unchanged (nullopt), three times in ten something: drawn
/// from their own stream, so the batch's other edits stay what the coverage guards expect.
std::optional<std::vector<Affine>> random_keys(const std::string& id, uint32_t i) {
    std::mt19937 rng(uint32_t(std::hash<std::string>{}(id)) ^ i);
    std::uniform_real_distribution<float> offset(-1.0f, 1.0f);
    if (rng() % 10 >= 3) return std::nullopt;
    std::vector<Affine> keys;
    for (uint32_t k = rng() % 2 ? 0 : 2 + rng() % 3; k > 0; --k)
        keys.push_back(Affine::translation({offset(rng), offset(rng), offset(rng)}));
    return keys;
}

}  // namespace

EditBatch ManyInstances::mixed_batch(int edits, bool allow_mesh_edits) {
    EditBatch b;
    std::vector<std::string> removed;  // an instance is not edited after its removal
    auto pick = [&]() -> Live* {
        for (int tries = 0; tries < 8 && !m_live.empty(); ++tries) {
            Live& l = m_live[std::size_t(integer(0, int(m_live.size()) - 1))];
            bool gone = false;
            for (const auto& r : removed) gone |= r == l.id;
            if (!gone) return &l;
        }
        return nullptr;
    };
    for (int i = 0; i < edits; ++i) {
        const int kind = integer(0, 99);
        Live* l = pick();
        if (kind < 38 && l) {
            b.edits.emplace_back(SetTransform{l->id, random_placement()});
        } else if (kind < 54 || !l) {
            AddInstance add;
            add.id = "i" + std::to_string(m_next++);
            add.mesh = m_meshes[std::size_t(integer(0, 3))];
            add.transform = random_placement();
            add.visible = chance(0.9);
            add.mask = chance(0.8) ? 0xFFFFFFFFu : 0x2u;
            m_live.push_back({add.id, add.visible});
            b.edits.emplace_back(std::move(add));
        } else if (kind < 68) {
            removed.push_back(l->id);
            b.edits.emplace_back(RemoveInstance{l->id});
        } else if (kind < 82) {
            UpdateInstance u;
            u.instance = l->id;
            l->visible = !l->visible;
            u.visible = l->visible;
            if (chance(0.3)) u.transform = random_placement();
            b.edits.emplace_back(std::move(u));
        } else if (kind < 97 || !allow_mesh_edits) {
            UpdateInstance u;
            u.instance = l->id;
            u.mask = chance(0.5) ? 0xFFFFFFFFu : (chance(0.5) ? 0x1u : 0x2u);
            if (m_keys) u.motion = random_keys(l->id, uint32_t(i));
            b.edits.emplace_back(std::move(u));
        } else {
            // A wobble refits a mesh's BLAS: every instance of it changes bounds.
            const std::size_t m = std::size_t(integer(0, 3));
            UpdateMeshPositions u;
            u.mesh = m_meshes[m];
            u.offset = 0;
            u.positions = m_shapes[m];
            for (Vec3& p : u.positions) p *= 1.0f + uniform(-0.15f, 0.15f);
            b.edits.emplace_back(std::move(u));
        }
    }
    // Forget the removed instances.
    for (const auto& id : removed) {
        for (std::size_t k = 0; k < m_live.size(); ++k) {
            if (m_live[k].id == id) {
                m_live[k] = m_live.back();
                m_live.pop_back();
                break;
            }
        }
    }
    return b;
}

}  // namespace strata::test

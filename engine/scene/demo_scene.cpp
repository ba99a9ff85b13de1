#include "engine/scene/demo_scene.h"

#include <cmath>
#include <string>

#include "engine/scene/shapes.h"

namespace strata {

namespace {

constexpr uint32_t FLAG_NX = 48;
constexpr uint32_t FLAG_NZ = 32;
constexpr uint32_t RING_COUNT = 12;
constexpr float RING_RADIUS = 4.0f;

AddMesh mesh(const std::string& id, MeshData data, const std::string& material,
             BuildOptions build = {}) {
    AddMesh e = add_mesh_edit(id, std::move(data), build);
    e.material = material;
    return e;
}

AddMaterial material(const std::string& id, Vec3 color, float roughness, float metallic,
                     Vec3 emission = Vec3(0.0f)) {
    return AddMaterial{id, Material{color, roughness, metallic, emission}};
}

AddInstance instance(const std::string& id, const std::string& mesh_id, const Affine& transform,
                     std::optional<std::string> mat = std::nullopt) {
    AddInstance e;
    e.id = id;
    e.mesh = mesh_id;
    e.transform = transform;
    e.material = std::move(mat);
    return e;
}

Affine ring_transform(uint32_t i, float phase) {
    const float a = 2.0f * 3.14159265f * float(i) / float(RING_COUNT) + phase;
    return Affine::translation({RING_RADIUS * std::cos(a), 0.5f, RING_RADIUS * std::sin(a)});
}

}  // namespace

std::vector<Vec3> demo_flag_positions(float t) {
    MeshData flag = make_plane(Vec3(3.0f, 1.0f, 2.0f), FLAG_NX, FLAG_NZ);
    for (Vec3& p : flag.positions) {
        // The plane lies in XZ; stand it up (z becomes height) and ripple it along x.
        const float along = p.x + 1.5f;
        const float height = p.z + 1.0f;
        const float wave = 0.18f * along * std::sin(3.0f * along - 4.0f * t);
        p = Vec3(p.x, height, wave);
    }
    return flag.positions;
}

EditBatch make_demo_scene() {
    EditBatch b;
    auto& e = b.edits;
    e.emplace_back(material("ground", {0.32f, 0.3f, 0.28f}, 0.9f, 0.0f));
    e.emplace_back(material("chrome", {0.9f, 0.9f, 0.92f}, 0.15f, 1.0f));
    e.emplace_back(material("clay", {0.8f, 0.35f, 0.2f}, 0.6f, 0.0f));
    e.emplace_back(material("teal", {0.1f, 0.55f, 0.55f}, 0.4f, 0.0f));
    e.emplace_back(material("gold", {1.0f, 0.77f, 0.34f}, 0.3f, 1.0f));
    e.emplace_back(material("lamp", {1.0f, 1.0f, 1.0f}, 1.0f, 0.0f, {3.0f, 2.6f, 2.0f}));
    e.emplace_back(material("flag", {0.85f, 0.15f, 0.2f}, 0.7f, 0.0f));

    e.emplace_back(mesh("ground", make_plane(Vec3(400.0f, 0.0f, 400.0f), 8, 8), "ground"));
    e.emplace_back(mesh("ball", make_sphere(1.5f, 160), "chrome"));
    e.emplace_back(mesh("pebble", make_sphere(0.5f, 72), "clay"));
    e.emplace_back(mesh("crate", make_box(Vec3(1.0f)), "teal"));
    MeshData flag = make_plane(Vec3(3.0f, 1.0f, 2.0f), FLAG_NX, FLAG_NZ);
    flag.positions = demo_flag_positions(0.0f);
    e.emplace_back(
        mesh("flag", std::move(flag), "flag", BuildOptions{BuildPreference::FastBuild, true}));

    e.emplace_back(instance("ground", "ground", Affine::identity()));
    e.emplace_back(instance("ball", "ball", Affine::translation({0.0f, 1.5f, 0.0f})));
    for (uint32_t i = 0; i < RING_COUNT; ++i) {
        e.emplace_back(instance("pebble-" + std::to_string(i), "pebble", ring_transform(i, 0.0f),
                                i % 3 == 0 ? std::optional<std::string>("gold") : std::nullopt));
    }
    e.emplace_back(instance(
        "crate-a", "crate",
        Affine::trs({-2.6f, 0.5f, 2.2f}, Affine::rotation_euler_deg({0, 30, 0}), Vec3(1.0f))));
    e.emplace_back(instance(
        "crate-b", "crate",
        Affine::trs({2.8f, 0.75f, 1.8f}, Affine::rotation_euler_deg({0, -20, 0}), Vec3(1.5f))));
    e.emplace_back(instance("lamp", "crate",
                            Affine::trs({0.0f, 4.5f, -3.0f}, Affine::identity(), Vec3(0.6f)),
                            std::string("lamp")));
    e.emplace_back(instance("flag", "flag", Affine::translation({-4.2f, 0.0f, -2.0f})));

    SetCamera cam;
    cam.eye = Vec3(0.0f, 4.0f, 11.0f);
    cam.target = Vec3(0.0f, 1.0f, 0.0f);
    cam.up = Vec3(0.0f, 1.0f, 0.0f);
    cam.fov_y_deg = 45.0f;
    e.emplace_back(cam);

    SetLighting light;
    light.sun_direction = Vec3(0.55f, 0.6f, 0.4f);
    light.sun_color = Vec3(2.2f, 2.0f, 1.75f);
    light.sky_color = Vec3(0.32f, 0.52f, 0.95f);
    light.sky_intensity = 0.9f;
    e.emplace_back(light);
    return b;
}

EditBatch make_demo_step(uint32_t step) {
    EditBatch b;
    auto& e = b.edits;
    const float t = 0.25f * float(step + 1);
    switch (step % DEMO_STEPS) {
        case 0: {  // camera only: no BVH work
            SetCamera cam;
            cam.eye = Vec3(5.0f, 4.0f, 10.0f);
            e.emplace_back(cam);
            break;
        }
        case 1:  // one instance moves: one TLAS update
            e.emplace_back(SetTransform{
                "crate-a", Affine::trs({-2.2f, 0.5f, 2.6f}, Affine::rotation_euler_deg({0, 55, 0}),
                                       Vec3(1.0f))});
            break;
        case 2:  // the whole ring moves: still one TLAS update
            for (uint32_t i = 0; i < RING_COUNT; ++i)
                e.emplace_back(SetTransform{"pebble-" + std::to_string(i), ring_transform(i, t)});
            break;
        case 3:  // the flag deforms: one refit
        case 4: {
            UpdateMeshPositions wave;
            wave.mesh = "flag";
            wave.positions = demo_flag_positions(t);
            e.emplace_back(std::move(wave));
            break;
        }
        case 5: {  // material and lighting only: no BVH work
            UpdateMaterial m;
            m.material = "teal";
            m.base_color = Vec3(0.2f, 0.3f, 0.75f);
            e.emplace_back(m);
            SetLighting l;
            l.sun_direction = Vec3(-0.5f, 0.7f, 0.4f);
            e.emplace_back(l);
            break;
        }
        case 6: {  // the ball gets finer: one BLAS rebuild (topology)
            MeshData finer = make_sphere(1.5f, 256);
            ReplaceMeshTopology topo;
            topo.mesh = "ball";
            topo.positions = std::move(finer.positions);
            topo.triangles = std::move(finer.triangles);
            e.emplace_back(std::move(topo));
            break;
        }
        default: {  // hide one crate, add a new mesh and instance
            UpdateInstance hide;
            hide.instance = "crate-b";
            hide.visible = false;
            e.emplace_back(hide);
            AddMesh extra = mesh("pillar", make_box(Vec3(0.6f, 3.0f, 0.6f)), "gold");
            e.emplace_back(std::move(extra));
            e.emplace_back(instance("pillar", "pillar", Affine::translation({3.0f, 1.5f, -1.5f})));
            break;
        }
    }
    return b;
}

}  // namespace strata

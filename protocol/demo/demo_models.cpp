#include "protocol/demo/demo_models.h"

#include <cmath>
#include <cstring>
#include <span>
#include <string>
#include <unordered_map>

#include "engine/scene/demo_scene.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/import.h"
#include "protocol/demo/demo_files.h"

namespace strata::demo {

namespace {

/// Where the model stands: behind and right of the ball, inside the ring of pebbles at every
/// phase of its motion (at most 3.27 from the axis; the pebbles start at 3.5), facing the camera
/// turned a little to the right, its hooves on the ground (the file's lowest point is
/// y = -0.736784).
constexpr float MODEL_SCALE = 1.25f;
constexpr float MODEL_FLOOR = 0.736784f;
Affine model_transform() {
    return Affine::trs({2.3f, MODEL_FLOOR * MODEL_SCALE, -1.3f},
                       Affine::rotation_euler_deg({0.0f, 20.0f, 0.0f}), Vec3(MODEL_SCALE));
}

std::string_view demo_file(std::string_view name) {
    for (const DemoFile& f : demo_files())
        if (f.path == name) return f.bytes;
    return {};
}

/// Exact bit patterns of a position: the key vertices at one place share.
struct PositionKey {
    uint32_t bits[3];
    friend bool operator==(const PositionKey&, const PositionKey&) = default;
};
struct PositionHash {
    std::size_t operator()(const PositionKey& k) const {
        return std::hash<uint64_t>()((uint64_t(k.bits[0]) << 32) ^ (uint64_t(k.bits[1]) << 16) ^
                                     k.bits[2]);
    }
};
PositionKey key_of(const Vec3& p) {
    PositionKey k{};
    std::memcpy(k.bits, &p, sizeof k.bits);
    return k;
}

}  // namespace

std::vector<Vec3> smooth_normals(const std::vector<Vec3>& positions,
                                 const std::vector<Triangle>& triangles) {
    // Step: one slot per distinct position.
    std::unordered_map<PositionKey, uint32_t, PositionHash> slot_of;
    std::vector<uint32_t> slot(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i)
        slot[i] = slot_of.try_emplace(key_of(positions[i]), uint32_t(slot_of.size())).first->second;
    // Step: area-weighted face normals summed per position (the cross product's length is
    // twice the area), then normalised.
    std::vector<Vec3> sum(slot_of.size(), Vec3(0.0f));
    for (const Triangle& t : triangles) {
        if (t.x >= positions.size() || t.y >= positions.size() || t.z >= positions.size())
            continue;
        const Vec3 n = glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]);
        for (uint32_t v : {t.x, t.y, t.z}) sum[slot[v]] += n;
    }
    std::vector<Vec3> normals(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const Vec3& s = sum[slot[i]];
        const float len = glm::length(s);
        normals[i] = len > 0.0f && std::isfinite(len) ? s / len : Vec3(0.0f, 1.0f, 0.0f);
    }
    return normals;
}

Result<EditBatch> scene_with_models() {
    EditBatch batch = make_demo_scene();

    const std::string_view obj = demo_file("spot.obj");
    const auto bytes = std::span(reinterpret_cast<const uint8_t*>(obj.data()), obj.size());
    auto asset = assets::import_asset(assets::AssetFormat::Obj, bytes, "spot.obj", {});
    if (!asset) return failure(ErrorCode::Internal, asset.error().detail);

    // The file has texture coordinates but no normals, and no material: smooth-shade it and
    // give it a coat (its texture is not part of the file).
    assets::AssetMaterial coat;
    coat.name = "coat";
    coat.material = Material{{0.86f, 0.8f, 0.7f}, 0.45f, 0.0f, Vec3(0.0f)};
    asset.value().materials.push_back(coat);
    for (assets::AssetMesh& m : asset.value().meshes) {
        if (m.normals.empty()) m.normals = smooth_normals(m.positions, m.triangles);
        m.material = int(asset.value().materials.size() - 1);
    }

    assets::BatchOptions options;
    options.prefix = std::string(MODEL_PREFIX);
    options.file = "spot.obj";
    assets::AssetBatch model = assets::asset_to_batch(std::move(asset.value()), options);
    for (Edit& e : model.batch.edits) {
        if (auto* g = std::get_if<AddGroup>(&e); g && g->id == MODEL_PREFIX)
            g->transform = model_transform();
        batch.edits.push_back(std::move(e));
    }
    return batch;
}

}  // namespace strata::demo

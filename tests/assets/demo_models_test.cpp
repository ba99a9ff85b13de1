// The demo scene's real model (protocol/demo): Spot imported from the compiled-in OBJ through the
// OBJ importer, smooth-shaded, standing on the ground clear of every other demo object; and the
// smooth normals it is shaded with.

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "protocol/demo/demo_models.h"

namespace strata {
namespace {

void expect_near(const Vec3& a, const Vec3& b) {
    EXPECT_NEAR(a.x, b.x, 1e-5f);
    EXPECT_NEAR(a.y, b.y, 1e-5f);
    EXPECT_NEAR(a.z, b.z, 1e-5f);
}

TEST(DemoModels, SmoothNormalsAverageTheFacesAroundAPositionAcrossSplitVertices) {
    MeshData box = make_box(Vec3(2.0f));
    // Corner 0 (-x, -y, -z) and corner 7 (+x, +y, +z) each lie on two triangles of each of their
    // three faces: their area-weighted normals point along the diagonals. The -x face then gets
    // its own copies of its corners, as a UV seam splits vertices in a real file.
    std::vector<Vec3> positions = box.positions;
    std::vector<Triangle> triangles = box.triangles;
    std::map<uint32_t, uint32_t> copy_of;
    for (std::size_t t : {8u, 9u}) {  // {0, 4, 6}, {0, 6, 2}: the -x face
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = triangles[t][k];
            auto [it, added] = copy_of.try_emplace(v, uint32_t(positions.size()));
            if (added) positions.push_back(positions[v]);
            v = it->second;
        }
    }
    ASSERT_EQ(positions.size(), 12u);
    const std::vector<Vec3> normals = demo::smooth_normals(positions, triangles);
    ASSERT_EQ(normals.size(), positions.size());
    expect_near(normals[0], glm::normalize(Vec3(-1.0f)));
    expect_near(normals[7], glm::normalize(Vec3(1.0f)));
    for (const auto& [original, copy] : copy_of) expect_near(normals[copy], normals[original]);
    for (const Vec3& n : normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);

    // Positions no triangle touches (or only degenerate ones) get +Y, never NaN.
    const std::vector<Vec3> lonely =
        demo::smooth_normals({Vec3(0.0f), Vec3(1.0f), Vec3(2.0f)}, {{0, 0, 1}});
    for (const Vec3& n : lonely) expect_near(n, Vec3(0.0f, 1.0f, 0.0f));
}

/// World-space box of a mesh's positions under a transform.
struct Box {
    Vec3 lo{INFINITY};
    Vec3 hi{-INFINITY};
    void add(const Vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    bool contains(const Vec3& p) const {
        return glm::all(glm::greaterThan(p, lo)) && glm::all(glm::lessThan(p, hi));
    }
};

TEST(DemoModels, TheDemoSceneHoldsSpotSmoothShadedOnTheGroundClearOfEverythingElse) {
    auto batch = demo::scene_with_models();
    ASSERT_TRUE(batch.has_value()) << batch.error().describe();

    std::map<std::string, const AddMesh*> meshes;
    std::map<std::string, Affine> groups;
    std::vector<const AddInstance*> instances;
    for (const Edit& e : batch.value().edits) {
        if (const auto* m = std::get_if<AddMesh>(&e)) meshes[m->id] = m;
        if (const auto* g = std::get_if<AddGroup>(&e)) groups[g->id] = g->transform;
        if (const auto* i = std::get_if<AddInstance>(&e)) instances.push_back(i);
    }
    // One mesh from the file, smooth-shaded, with its texture coordinates, in a group "spot".
    const std::string prefix(demo::MODEL_PREFIX);
    const AddMesh* spot = nullptr;
    for (const auto& [id, m] : meshes)
        if (id.rfind(prefix + ".", 0) == 0) spot = m;
    ASSERT_NE(spot, nullptr);
    EXPECT_EQ(spot->triangles.size(), 5856u);
    ASSERT_EQ(spot->normals.size(), spot->positions.size());
    ASSERT_EQ(spot->uvs.size(), spot->positions.size());
    ASSERT_TRUE(groups.count(prefix));

    // Spot's world positions: its group's transform, then its instance's.
    const AddInstance* spot_instance = nullptr;
    for (const AddInstance* i : instances)
        if (i->mesh == spot->id) spot_instance = i;
    ASSERT_NE(spot_instance, nullptr);
    ASSERT_EQ(spot_instance->parent, std::optional<std::string>(prefix));
    const Affine to_world = groups[prefix] * spot_instance->transform;
    std::vector<Vec3> world;
    for (const Vec3& p : spot->positions) world.push_back(to_world.transform_point(p));
    float lowest = INFINITY;
    for (const Vec3& p : world) lowest = std::min(lowest, p.y);
    EXPECT_NEAR(lowest, 0.0f, 1e-3f) << "Spot's hooves rest on the ground plane (y = 0)";

    // No vertex of Spot is inside the box of any other instance (the ground aside).
    for (const AddInstance* i : instances) {
        if (i == spot_instance || i->id == "ground") continue;
        ASSERT_TRUE(meshes.count(i->mesh)) << i->mesh;
        Box box;
        for (const Vec3& p : meshes[i->mesh]->positions) box.add(i->transform.transform_point(p));
        const auto inside = std::count_if(world.begin(), world.end(),
                                          [&](const Vec3& p) { return box.contains(p); });
        EXPECT_EQ(inside, 0) << "Spot overlaps " << i->id;
    }

    // The whole batch is one valid scene at version 1.
    auto engine = Engine::create();
    ASSERT_TRUE(engine.has_value());
    auto applied = engine.value()->apply(std::move(batch.value()));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    EXPECT_EQ(applied.value().version, 1u);
}

}  // namespace
}  // namespace strata

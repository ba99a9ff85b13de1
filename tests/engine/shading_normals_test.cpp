// Shading normals: a mesh's interpolated vertex normals drive shading (a coarse sphere looks
// round), and they never let light through the true surface.

#include <cmath>

#include <gtest/gtest.h>

#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

using test::apply_ok;

/// A coarse sphere at the origin, with the sphere's own normals when `smooth`.
AddMesh coarse_sphere(const std::string& id, bool smooth) {
    AddMesh m = test::mesh_edit(id, make_sphere(1.0f, 8));
    if (smooth) {
        for (const Vec3& p : m.positions) m.normals.push_back(glm::normalize(p));
    }
    return m;
}

/// Mean angle (radians) between the normal AOV and the direction from the sphere's centre to the
/// hit point, over the pixels that hit.
double mean_error_to_round_normal(bool smooth) {
    auto engine = test::make_engine();
    apply_ok(*engine, coarse_sphere("s", smooth), test::instance_edit("s1", "s"),
             SetCamera{Vec3(0, 0, 4), Vec3(0), Vec3(0, 1, 0), 40.0f});
    const Frame f =
        test::render_frame_ok(*engine, test::request(64, 64, 1, {Aov::Normal, Aov::Position}));
    double sum = 0.0;
    std::size_t hits = 0;
    for (std::size_t p = 0; p < f.buffers.normal.size(); ++p) {
        const Vec3 pos = f.buffers.position[p];
        const Vec3 n = f.buffers.normal[p];
        if (glm::length(pos) < 0.5f || glm::length(n) < 0.5f) continue;
        const float c = glm::dot(glm::normalize(n), glm::normalize(pos));
        sum += std::acos(std::clamp(double(c), -1.0, 1.0));
        ++hits;
    }
    EXPECT_GT(hits, 500u);
    return hits ? sum / double(hits) : 0.0;
}

TEST(ShadingNormals, InterpolatedNormalsFollowTheRoundSurface) {
    const double faceted = mean_error_to_round_normal(false);
    const double smooth = mean_error_to_round_normal(true);
    // An 8-segment sphere's facets are off by up to ~22 degrees; interpolation by a few.
    EXPECT_GT(faceted, 0.08);
    EXPECT_LT(smooth, 0.5 * faceted) << "faceted " << faceted << " smooth " << smooth;
}

/// The mean red of a frame of a floor (y = 0, facing up) whose normals all lean toward +x, lit
/// only by a sun in `sun_direction`, seen from above.
double floor_brightness(const Vec3& sun_direction, bool leaning_normals) {
    auto engine = test::make_engine();
    AddMesh floor = test::mesh_edit("floor", make_plane(Vec3(4.0f), 2, 2));
    if (leaning_normals) floor.normals.assign(floor.positions.size(), Vec3(1.0f, 0.3f, 0.0f));
    SetLighting light{sun_direction, Vec3(1.0f), Vec3(0.0f), 0.0f};
    apply_ok(*engine, floor, test::instance_edit("f", "floor"), light,
             SetCamera{Vec3(0, 3, 1), Vec3(0), Vec3(0, 1, 0), 30.0f});
    const Frame f = test::render_frame_ok(*engine, test::request(32, 32, 4));
    double sum = 0.0;
    for (const Vec3& c : f.buffers.color) sum += double(c.x);
    return sum / double(f.buffers.color.size());
}

TEST(ShadingNormals, NoLightLeaksThroughTheSurface) {
    // The sun is just below the floor; the shading normals lean toward it.
    const Vec3 below(1.0f, -0.2f, 0.0f);
    EXPECT_EQ(floor_brightness(below, true), 0.0);
    EXPECT_EQ(floor_brightness(below, false), 0.0);
    // Just above the floor on the side the normals lean to: lit, and brighter than flat.
    const Vec3 above(1.0f, 0.2f, 0.0f);
    const double flat = floor_brightness(above, false);
    EXPECT_GT(flat, 0.01);
    EXPECT_GT(floor_brightness(above, true), 2.0 * flat);
    // Above the floor on the other side: the leaning normals turn away from the sun.
    EXPECT_LT(floor_brightness(Vec3(-1.0f, 0.2f, 0.0f), true), 0.5 * flat);
}

TEST(ShadingNormals, ANormalsEditChangesTheNextFrame) {
    auto engine = test::make_engine();
    apply_ok(*engine, coarse_sphere("s", false), test::instance_edit("s1", "s"),
             SetCamera{Vec3(0, 0, 4), Vec3(0), Vec3(0, 1, 0), 40.0f});
    const Frame faceted = test::render_frame_ok(*engine, test::request(48, 48, 4));
    UpdateMeshPositions smooth;
    smooth.mesh = "s";
    smooth.normals = coarse_sphere("s", true).normals;
    apply_ok(*engine, smooth);
    const Frame round = test::render_frame_ok(*engine, test::request(48, 48, 4));
    EXPECT_TRUE(round.info.report.no_accel_work());
    EXPECT_GT(test::rms_difference(faceted.buffers.color, round.buffers.color), 0.01);
    UpdateMeshPositions back;
    back.mesh = "s";
    back.normals = std::vector<Vec3>{};
    apply_ok(*engine, back);
    const Frame again = test::render_frame_ok(*engine, test::request(48, 48, 4));
    EXPECT_EQ(test::rms_difference(faceted.buffers.color, again.buffers.color), 0.0);
}

}  // namespace
}  // namespace strata

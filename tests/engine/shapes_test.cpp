#include <gtest/gtest.h>

#include "engine/scene/shapes.h"

namespace strata {
namespace {

bool indices_valid(const MeshData& m) {
    for (const Triangle& t : m.triangles) {
        if (t.x >= m.positions.size() || t.y >= m.positions.size() || t.z >= m.positions.size()) return false;
    }
    return true;
}

TEST(Shapes, SphereTriangleCountFollowsTheSegmentCount) {
    for (uint32_t segments : {3u, 4u, 17u, 64u}) {
        const MeshData s = make_sphere(2.0f, segments);
        EXPECT_EQ(s.triangles.size(), sphere_triangle_count(segments)) << segments;
        EXPECT_TRUE(indices_valid(s));
        for (const Vec3& p : s.positions) EXPECT_NEAR(glm::length(p), 2.0f, 1e-5f);
    }
    EXPECT_NEAR(double(sphere_triangle_count(1000)), 1e6, 1e4) << "1000 segments is about a million";
}

TEST(Shapes, SphereIsClosedAndOutwardFacing) {
    const MeshData s = make_sphere(1.0f, 12);
    double volume = 0.0;  // divergence theorem: positive for outward-facing triangles
    for (const Triangle& t : s.triangles) {
        volume += double(glm::dot(s.positions[t.x], glm::cross(s.positions[t.y], s.positions[t.z]))) / 6.0;
    }
    EXPECT_GT(volume, 3.0);
    EXPECT_LT(volume, 4.19);
}

TEST(Shapes, BoxAndPlaneHaveTheDocumentedSize) {
    const MeshData box = make_box(Vec3(1.0f, 2.0f, 3.0f));
    EXPECT_EQ(box.positions.size(), 8u);
    EXPECT_EQ(box.triangles.size(), 12u);
    EXPECT_TRUE(indices_valid(box));
    const MeshData plane = make_plane(Vec3(4.0f, 0.0f, 2.0f), 3, 5);
    EXPECT_EQ(plane.positions.size(), 4u * 6u);
    EXPECT_EQ(plane.triangles.size(), 2u * 3u * 5u);
    EXPECT_TRUE(indices_valid(plane));
    const Vec3 n = glm::cross(plane.positions[plane.triangles[0].y] - plane.positions[plane.triangles[0].x],
                              plane.positions[plane.triangles[0].z] - plane.positions[plane.triangles[0].x]);
    EXPECT_GT(n.y, 0.0f) << "plane faces +Y";
}

}  // namespace
}  // namespace strata

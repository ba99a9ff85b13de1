// Frames against stored reference images (the demo scene; a coarse sphere with and without
// shading normals), compared with a tolerance: Embree and libm
// pick different code paths on different CPUs, so the bytes may differ slightly across machines
// (on one machine they never do, see render_determinism_test).
//
// Regenerate after an intended change of the renderer or of the demo scene, then look at it:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R ReferenceImage
// On a mismatch the test writes the frame it got to <name>_actual.png in its working
// directory (build/tests/engine under ctest).


#include <gtest/gtest.h>

#include "engine/scene/demo_scene.h"
#include "tests/engine/reference_image.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

constexpr uint32_t WIDTH = 320, HEIGHT = 180, SPP = 16;

/// Compares `image` (a WIDTH x HEIGHT PNG unless told) with the stored `name`, or rewrites it.
void expect_matches_reference(const std::string& name, const EncodedFrame& image,
                              uint32_t width = WIDTH, uint32_t height = HEIGHT) {
    test::expect_matches_reference(STRATA_TEST_DATA_DIR, name, image, width, height);
}

TEST(ReferenceImage, DemoSceneMatchesTheStoredFrame) {
    auto engine = test::engine_with(make_demo_scene());
    expect_matches_reference(
        "demo_reference",
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png)));
}

/// A 12-segment sphere on a floor, lit by the default sun and sky; with the sphere's own
/// normals when `smooth`.
EncodedFrame sphere_frame(bool smooth) {
    auto engine = test::make_engine();
    AddMesh ball = test::mesh_edit("ball", make_sphere(1.0f, 12));
    if (smooth) {
        for (const Vec3& p : ball.positions) ball.normals.push_back(glm::normalize(p));
    }
    AddMaterial clay{"clay", Material{Vec3(0.8f, 0.45f, 0.3f), 0.6f, 0.0f, Vec3(0.0f)}};
    ball.material = "clay";
    test::apply_ok(*engine, clay, ball, test::instance_edit("ball-1", "ball", {0, 1, 0}),
                   test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)),
                   test::instance_edit("floor-1", "floor"),
                   SetCamera{Vec3(0, 2, 4.5f), Vec3(0, 0.8f, 0), Vec3(0, 1, 0), 40.0f});
    return test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png));
}

TEST(ReferenceImage, SmoothAndFacetedSpheresMatchTheirStoredFrames) {
    const EncodedFrame smooth = sphere_frame(true);
    const EncodedFrame faceted = sphere_frame(false);
    EXPECT_NE(smooth.bytes, faceted.bytes);
    expect_matches_reference("sphere_smooth_reference", smooth);
    expect_matches_reference("sphere_faceted_reference", faceted);
}

}  // namespace
}  // namespace strata

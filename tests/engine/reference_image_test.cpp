// Frames against stored reference images (the demo scene; a coarse sphere with and without
// shading normals; a fur ball of curves; a point cloud; a spinning wheel with motion blur; a
// field of level-of-detail objects from near and far),
// compared with a tolerance: Embree and libm pick different code paths on different CPUs, so
// the bytes may differ slightly across machines (on one machine they never do, see
// render_determinism_test).
//
// Regenerate after an intended change of the renderer or of the demo scene, then look at it:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R ReferenceImage
// On a mismatch the test writes the frame it got to <name>_actual.png in its working
// directory (build/tests/engine under ctest).

#include <cmath>

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

/// A fur ball: a sphere with 600 round B-spline hairs of tapering radius, on a floor.
TEST(ReferenceImage, AFurBallOfCurvesMatchesItsStoredFrame) {
    auto engine = test::make_engine();
    AddMesh hair;
    hair.id = "hair";
    hair.kind = MeshKind::Curves;
    hair.basis = CurveBasis::BSpline;
    const float golden = 2.39996323f;
    for (int k = 0; k < 600; ++k) {
        const float z = 1.0f - 2.0f * (float(k) + 0.5f) / 600.0f, r = std::sqrt(1.0f - z * z);
        const Vec3 n(r * std::cos(golden * float(k)), z, r * std::sin(golden * float(k)));
        const Vec3 droop(0.0f, -0.12f, 0.0f);
        hair.strands.push_back(5);
        for (int c = 0; c < 5; ++c) {
            const float t = float(c) / 4.0f;
            hair.positions.push_back(n * (0.95f + 0.55f * t) + droop * t * t);
            hair.radii.push_back(0.025f * (1.0f - 0.8f * t));
        }
    }
    hair.material = "fur";
    AddMesh ball = test::mesh_edit("ball", make_sphere(1.0f, 24));
    ball.material = "fur";
    const AddMaterial fur{"fur", Material{Vec3(0.75f, 0.5f, 0.25f), 0.7f, 0.0f, Vec3(0.0f)}};
    test::apply_ok(*engine, fur,
                   hair, ball, test::instance_edit("hair-1", "hair", {0, 1.5f, 0}),
                   test::instance_edit("ball-1", "ball", {0, 1.5f, 0}),
                   test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)),
                   test::instance_edit("floor-1", "floor"),
                   SetCamera{Vec3(0, 2.5f, 5.5f), Vec3(0, 1.3f, 0), Vec3(0, 1, 0), 40.0f});
    expect_matches_reference(
        "fur_ball_reference",
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png)));
}

/// A point cloud: 3,000 spheres of varying radius on a spiral, on a floor.
TEST(ReferenceImage, APointCloudMatchesItsStoredFrame) {
    auto engine = test::make_engine();
    AddMesh cloud;
    cloud.id = "cloud";
    cloud.kind = MeshKind::Points;
    for (int k = 0; k < 3000; ++k) {
        const float t = float(k) / 3000.0f, a = 40.0f * t;
        const float wobble = 0.15f * std::sin(float(k) * 12.9898f);
        cloud.positions.emplace_back((0.4f + 1.6f * t) * std::cos(a), 0.2f + 2.0f * t + wobble,
                                     (0.4f + 1.6f * t) * std::sin(a));
        cloud.radii.push_back(0.02f + 0.05f * t);
    }
    cloud.material = "blue";
    const AddMaterial blue{"blue", Material{Vec3(0.2f, 0.4f, 0.85f), 0.3f, 0.0f, Vec3(0.0f)}};
    test::apply_ok(*engine, blue,
                   cloud, test::instance_edit("cloud-1", "cloud"),
                   test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)),
                   test::instance_edit("floor-1", "floor"),
                   SetCamera{Vec3(0, 3.0f, 6.0f), Vec3(0, 1.1f, 0), Vec3(0, 1, 0), 45.0f});
    expect_matches_reference(
        "point_cloud_reference",
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png)));
}

/// A wheel of six spokes turning 24 degrees while the shutter is open (nine motion keys each),
/// its hub still, in front of a painted wall: the spokes blur along their arcs.
TEST(ReferenceImage, ASpinningWheelIsMotionBlurred) {
    auto engine = test::make_engine();
    EditBatch b;
    b.edits.emplace_back(
        AddMaterial{"steel", Material{Vec3(0.7f, 0.7f, 0.75f), 0.3f, 1.0f, Vec3(0.0f)}});
    AddMesh spoke = test::mesh_edit("spoke", make_box(Vec3(0.12f, 1.6f, 0.12f)));
    spoke.material = "steel";
    b.edits.emplace_back(std::move(spoke));
    b.edits.emplace_back(test::mesh_edit("hub", make_sphere(0.25f, 24)));
    b.edits.emplace_back(
        AddMaterial{"paint", Material{Vec3(0.8f, 0.5f, 0.25f), 0.8f, 0.0f, Vec3(0.0f)}});
    AddMesh wall_mesh = test::mesh_edit("wall", make_plane(Vec3(10.0f), 1, 1));
    wall_mesh.material = "paint";
    b.edits.emplace_back(std::move(wall_mesh));
    b.edits.emplace_back(AddGroup{"wheel", std::nullopt, Affine::translation({0, 1.5f, 0}), true});
    for (int s = 0; s < 6; ++s) {
        AddInstance i = test::instance_edit("spoke-" + std::to_string(s), "spoke");
        i.parent = "wheel";
        for (int k = 0; k < 9; ++k) {
            const float deg = 60.0f * float(s) + 24.0f * float(k) / 8.0f;
            i.motion.push_back(Affine::rotation_euler_deg({0, 0, deg}) *
                               Affine::translation({0, 0.8f, 0}));
        }
        b.edits.emplace_back(std::move(i));
    }
    AddInstance hub = test::instance_edit("hub-1", "hub");
    hub.parent = "wheel";
    b.edits.emplace_back(std::move(hub));
    AddInstance wall = test::instance_edit("wall-1", "wall");
    wall.transform = Affine::trs({0, 1.5f, -1}, Affine::rotation_euler_deg({90, 0, 0}), Vec3(1.0f));
    b.edits.emplace_back(std::move(wall));
    SetCamera camera{Vec3(0, 1.5f, 5.0f), Vec3(0, 1.5f, 0), Vec3(0, 1, 0), 45.0f};
    camera.shutter_open = 0.0f;
    camera.shutter_close = 1.0f;
    b.edits.emplace_back(camera);
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    expect_matches_reference(
        "motion_blur_reference",
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, 64, {}, ImageFormat::Png)));
}

/// A field of 9x9 level-of-detail groups on a floor in the sun: each draws a smooth blue sphere
/// up to 9 units from the camera and an orange box beyond. Near, the first rows are spheres and
/// the rest boxes; far, all are boxes. Shadow rays measure from the camera too, so boxes cast
/// box shadows and no sphere is shadowed by its own box at the switch.
TEST(ReferenceImage, AFieldOfLevelsOfDetailFromNearAndFar) {
    auto engine = test::make_engine();
    EditBatch b;
    b.edits.emplace_back(
        AddMaterial{"blue", Material{Vec3(0.2f, 0.35f, 0.8f), 0.4f, 0.0f, Vec3(0.0f)}});
    b.edits.emplace_back(
        AddMaterial{"orange", Material{Vec3(0.9f, 0.45f, 0.1f), 0.6f, 0.0f, Vec3(0.0f)}});
    MeshData sphere = make_sphere(0.4f, 32);
    AddMesh fine = test::mesh_edit("fine", sphere);
    fine.normals = sphere.positions;  // a sphere at the origin: its positions are its normals
    fine.material = "blue";
    AddMesh coarse = test::mesh_edit("coarse", make_box(Vec3(0.7f)));
    coarse.material = "orange";
    b.edits.emplace_back(std::move(fine));
    b.edits.emplace_back(std::move(coarse));
    b.edits.emplace_back(test::mesh_edit("floor", make_plane(Vec3(30.0f), 1, 1)));
    b.edits.emplace_back(test::instance_edit("floor-1", "floor", {0, -0.4f, 0}));
    for (int i = 0; i < 81; ++i) {
        const std::string id = "g" + std::to_string(i);
        AddGroup g{id, std::nullopt,
                   Affine::translation({1.5f * float(i % 9 - 4), 0.0f, -1.5f * float(i / 9)}),
                   true};
        g.lod = true;
        b.edits.emplace_back(std::move(g));
        AddInstance near = test::instance_edit(id + ".fine", "fine");
        near.parent = id;
        near.lod_far = 9.0f;
        AddInstance far = test::instance_edit(id + ".coarse", "coarse");
        far.parent = id;
        far.lod_near = 9.0f;
        b.edits.emplace_back(std::move(near));
        b.edits.emplace_back(std::move(far));
    }
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    for (const auto& [name, eye] : {std::pair{"lod_near_reference", Vec3(0, 2.5f, 4.0f)},
                                    std::pair{"lod_far_reference", Vec3(0, 9.0f, 16.0f)}}) {
        test::apply_ok(*engine, SetCamera{eye, Vec3(0, 0, -5), Vec3(0, 1, 0), 50.0f});
        expect_matches_reference(
            name,
            test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png)));
    }
}

}  // namespace
}  // namespace strata

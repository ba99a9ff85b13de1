// Known answers for the geometry AOVs: depth of a plane, coverage of a sphere, which instance and
// mesh each pixel shows, and ids that follow a moved instance.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "engine/render/camera_rays.h"
#include "engine/render/shading.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::camera_edit;
using test::instance_edit;
using test::mesh_edit;
using test::project;
using test::render_frame_ok;
using test::request;

const std::vector<Aov> GEOMETRY_AOVS = {Aov::Depth,       Aov::Position, Aov::InstanceId,
                                        Aov::PrimitiveId, Aov::MeshId,   Aov::Normal};

/// A large plane facing the camera from distance d (the plane is y = 0, the camera looks down).
std::unique_ptr<Engine> plane_at(float d) {
    auto engine = test::make_engine();
    Camera cam;
    cam.eye = Vec3(0.0f, d, 0.0f);
    cam.target = Vec3(0.0f);
    cam.up = Vec3(0.0f, 0.0f, -1.0f);
    cam.fov_y_deg = 50.0f;
    apply_ok(*engine, mesh_edit("plane", make_plane(Vec3(1000.0f, 0.0f, 1000.0f), 4, 4)),
             instance_edit("plane", "plane"), camera_edit(cam));
    return engine;
}

class PlaneDepth : public ::testing::TestWithParam<float> {};

TEST_P(PlaneDepth, CentrePixelDepthIsTheDistance) {
    const float d = GetParam();
    auto engine = plane_at(d);
    // An odd size puts the centre pixel's ray exactly on the optical axis.
    const Frame f = render_frame_ok(*engine, request(33, 21, 2, GEOMETRY_AOVS));
    const std::size_t centre = std::size_t(10) * 33 + 16;
    EXPECT_NEAR(f.buffers.depth[centre], d, d * 2e-6f);
    EXPECT_NEAR(f.buffers.position[centre].y, 0.0f, d * 2e-6f);
    EXPECT_NEAR(f.buffers.normal[centre].y, 1.0f, 1e-6f);
    // Off-centre pixels are farther: depth is along the ray, not the view axis.
    EXPECT_GT(f.buffers.depth[0], d * 1.1f);
}

INSTANTIATE_TEST_SUITE_P(Distances, PlaneDepth, ::testing::Values(0.5f, 3.0f, 7.25f, 120.0f));

TEST(RenderKnownAnswer, PixelsThatHitNothingHaveTheDocumentedValues) {
    auto engine = test::make_engine();
    apply_ok(*engine, mesh_edit("box", make_box(Vec3(1.0f))),
             instance_edit("box", "box", {0, 0, 50}));
    const Frame f =
        render_frame_ok(*engine, request(16, 16, 1,
                                         {Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Position,
                                          Aov::InstanceId, Aov::PrimitiveId, Aov::MeshId}));
    const SkyModel sky{Lighting{}};
    for (std::size_t i = 0; i < f.buffers.pixel_count(); ++i) {
        ASSERT_EQ(f.buffers.depth[i], std::numeric_limits<float>::infinity());
        ASSERT_EQ(f.buffers.instance_id[i], MISS_ID);
        ASSERT_EQ(f.buffers.primitive_id[i], MISS_ID);
        ASSERT_EQ(f.buffers.mesh_id[i], MISS_ID);
        ASSERT_EQ(f.buffers.position[i], Vec3(0.0f));
        ASSERT_EQ(f.buffers.albedo[i], Vec3(0.0f));
        ASSERT_EQ(f.buffers.normal[i], Vec3(0.0f));
        // The background is the sky; the default camera looks slightly down, below the horizon.
        ASSERT_GT(f.buffers.color[i].z, 0.0f);
    }
}

TEST(RenderKnownAnswer, SphereSilhouetteCoversTheProjectedDisc) {
    auto engine = test::make_engine();
    const float radius = 1.0f, distance = 5.0f, fov = 40.0f;
    Camera cam;
    cam.eye = Vec3(0.0f, 0.0f, distance);
    cam.target = Vec3(0.0f);
    cam.fov_y_deg = fov;
    apply_ok(*engine, mesh_edit("sphere", make_sphere(radius, 512)),
             instance_edit("sphere", "sphere"), camera_edit(cam));
    const uint32_t w = 241, h = 201;
    const Frame f = render_frame_ok(*engine, request(w, h, 1, {Aov::InstanceId}));
    std::size_t covered = 0;
    for (uint32_t id : f.buffers.instance_id) covered += id != MISS_ID;
    // The silhouette is the cone of half-angle asin(r / D): a circle of radius tan of that on
    // the image plane at unit distance, where h / 2 pixels span tan(fov / 2).
    const double half_angle = std::asin(double(radius) / double(distance));
    const double r_px = std::tan(half_angle) / std::tan(glm::radians(double(fov)) / 2) * (h / 2.0);
    const double expected = std::numbers::pi * r_px * r_px;
    EXPECT_NEAR(double(covered), expected, expected * 0.005) << "radius " << r_px << " px";
}

/// Three boxes in a row (two meshes) in front of a camera, nothing behind them.
class SeparatedInstances : public ::testing::Test {
protected:
    void SetUp() override {
        engine = test::make_engine();
        cam.eye = Vec3(0.0f, 0.0f, 12.0f);
        cam.target = Vec3(0.0f);
        apply_ok(*engine, mesh_edit("cube", make_box(Vec3(1.5f))),
                 mesh_edit("ball", make_sphere(0.8f, 48)), instance_edit("left", "cube", LEFT),
                 instance_edit("middle", "ball", MIDDLE), instance_edit("right", "cube", RIGHT),
                 camera_edit(cam));
    }

    uint32_t slot(const char* instance) const {
        return engine->read([&](const Scene& s) { return s.find_instance(instance).index; });
    }
    uint32_t mesh_slot(const char* mesh) const {
        return engine->read([&](const Scene& s) { return s.find_mesh(mesh).index; });
    }
    Frame render() const {
        return render_frame_ok(*engine,
                               request(W, H, 1, {Aov::InstanceId, Aov::MeshId, Aov::PrimitiveId}));
    }
    std::size_t at(const Vec3& p) const { return test::pixel_index(W, project(cam, W, H, p)); }

    static constexpr uint32_t W = 160, H = 90;
    static constexpr Vec3 LEFT{-4.0f, 0.0f, 0.0f}, MIDDLE{0.0f, 0.0f, 0.0f},
        RIGHT{4.0f, 0.0f, 0.0f};
    std::unique_ptr<Engine> engine;
    Camera cam;
};

TEST_F(SeparatedInstances, InstanceIdNamesTheInstanceUnderEachPixel) {
    const Frame f = render();
    const FrameBuffers& b = f.buffers;
    const struct {
        const char* instance;
        const char* mesh;
        Vec3 at;
    } expected[] = {{"left", "cube", LEFT}, {"middle", "ball", MIDDLE}, {"right", "cube", RIGHT}};
    for (const auto& e : expected) {
        const std::size_t p = at(e.at);
        EXPECT_EQ(b.instance_id[p], slot(e.instance)) << e.instance;
        EXPECT_EQ(b.mesh_id[p], mesh_slot(e.mesh)) << e.instance;
        EXPECT_NE(b.primitive_id[p], MISS_ID) << e.instance;
    }
    // Between the instances, and above them, nothing is hit.
    for (const Vec3 gap :
         {Vec3(-2.0f, 0.0f, 0.0f), Vec3(2.0f, 0.0f, 0.0f), Vec3(0.0f, 2.5f, 0.0f)}) {
        EXPECT_EQ(b.instance_id[at(gap)], MISS_ID);
        EXPECT_EQ(b.mesh_id[at(gap)], MISS_ID);
        EXPECT_EQ(b.primitive_id[at(gap)], MISS_ID);
    }
    // Every pixel names one of the three instances or nothing, and its mesh matches.
    std::size_t counts[3] = {};
    const uint32_t slots[3] = {slot("left"), slot("middle"), slot("right")};
    for (std::size_t i = 0; i < b.pixel_count(); ++i) {
        if (b.instance_id[i] == MISS_ID) continue;
        const auto k = std::find(slots, slots + 3, b.instance_id[i]) - slots;
        ASSERT_LT(k, 3) << "pixel " << i << " names unknown instance " << b.instance_id[i];
        ++counts[k];
        EXPECT_EQ(b.mesh_id[i], mesh_slot(k == 1 ? "ball" : "cube"));
        EXPECT_LT(b.primitive_id[i], k == 1 ? make_sphere(0.8f, 48).triangles.size() : 12u);
    }
    EXPECT_GT(counts[0], 100u);
    // The cubes are mirror images (up to rounding of the ray directions along their edges).
    EXPECT_NEAR(double(counts[0]), double(counts[2]), 0.02 * double(counts[0]));
    EXPECT_GT(counts[1], 100u);
}

TEST_F(SeparatedInstances, MovedInstanceIdsMoveWithIt) {
    const uint32_t middle = slot("middle");
    const Frame before = render();
    const Vec3 moved(0.0f, 2.0f, 0.0f);
    apply_ok(*engine, SetTransform{"middle", Affine::translation(moved)});
    const Frame after = render();

    EXPECT_EQ(before.buffers.instance_id[at(MIDDLE)], middle);
    EXPECT_EQ(after.buffers.instance_id[at(MIDDLE)], MISS_ID);
    EXPECT_EQ(after.buffers.instance_id[at(moved)], middle);
    EXPECT_EQ(after.info.version, before.info.version + 1);

    // The whole footprint shifts by the projected offset; the other instances stay put.
    const int dy = int(std::lround(project(cam, W, H, moved).y - project(cam, W, H, MIDDLE).y));
    std::size_t footprint = 0, shifted = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const std::size_t p = std::size_t(y) * W + x;
            if (before.buffers.instance_id[p] != middle) {
                if (before.buffers.instance_id[p] != MISS_ID) {
                    EXPECT_EQ(after.buffers.instance_id[p], before.buffers.instance_id[p]);
                }
                continue;
            }
            ++footprint;
            const int ty = int(y) + dy;
            if (ty >= 0 && ty < int(H) &&
                after.buffers.instance_id[std::size_t(ty) * W + x] == middle)
                ++shifted;
        }
    }
    ASSERT_GT(footprint, 100u);
    // Perspective changes the footprint a little off-axis; nearly all of it lands shifted.
    EXPECT_GT(double(shifted), 0.95 * double(footprint));
}

}  // namespace
}  // namespace strata

namespace strata {
namespace {

/// Centre-pixel hit of a camera looking (almost) straight down at the pole of a UV sphere, where
/// a fan of `segments` triangles meets in one vertex: the centre ray passes through that vertex.
struct PoleHit {
    uint32_t instance;
    float distance;
};

PoleHit look_down_at_pole(bool watertight, uint32_t segments, float radius) {
    EngineConfig config;
    config.accel.watertight = watertight;
    auto engine = std::move(test::create_engine(config).value());
    SetCamera down;
    down.eye = Vec3(0.0f, 12.0f, 0.01f);
    down.target = Vec3(0.0f);
    EXPECT_TRUE(engine
                    ->apply(EditBatch{{test::mesh_edit("ball", make_sphere(radius, segments)),
                                       test::instance_edit("ball", "ball", {0, radius, 0}), down}})
                    .has_value());
    PrimarySettings s;
    s.width = 9;
    s.height = 9;
    const FrameBuffers hits = std::move(engine->render_primary(s).value().buffers);
    const std::size_t centre = 4 * 9 + 4;
    return {hits.instance_id[centre], hits.depth[centre]};
}

TEST(RenderKnownAnswer, ARayThroughAVertexSharedByManyTrianglesHitsTheSurface) {
    // Embree's default (non-watertight) triangle test lets this very ray through the pole in each
    // of these meshes on the development machine; watertight mode must never.
    for (const auto& [segments, radius] :
         {std::pair{64u, 1.0f}, {96u, 1.0f}, {192u, 1.0f}, {192u, 1.5f}}) {
        const PoleHit hit = look_down_at_pole(true, segments, radius);
        ASSERT_NE(hit.instance, INVALID_ID)
            << "the ray slipped between the pole's triangles (" << segments << " segments)";
        EXPECT_NEAR(hit.distance, 12.0f - 2.0f * radius, 1e-4f);
    }
}

/// Applies `edits` as one batch and traces a width x height primary frame.
FrameBuffers primary_frame(Engine& engine, std::vector<Edit> edits, uint32_t width,
                           uint32_t height) {
    EditBatch batch;
    batch.edits = std::move(edits);
    EXPECT_TRUE(engine.apply(std::move(batch)).has_value());
    PrimarySettings s;
    s.width = width;
    s.height = height;
    return std::move(engine.render_primary(s).value().buffers);
}

/// The instance slots (the instance_id AOV's values) of instances `ids`.
std::vector<uint32_t> instance_slots(Engine& engine, const std::vector<std::string>& ids) {
    return engine.read([&](const Scene& sc) {
        std::vector<uint32_t> out;
        for (const std::string& id : ids) out.push_back(sc.find_instance(id).index);
        return out;
    });
}

TEST(RenderKnownAnswer, ThePrimaryPreviewIsBaseColourLitBySunAndSkyPlusEmissionTimesTextures) {
    // A quad with uvs, four times with four materials: plain; the same with white base-colour
    // and emissive textures (the textured path, which must give the same colour); a red
    // base-colour texture; unlit.
    MeshData quad;
    quad.positions = {{-1, 0, -1}, {1, 0, -1}, {-1, 0, 1}, {1, 0, 1}};
    quad.triangles = {{0, 2, 1}, {1, 2, 3}};
    AddMesh mesh = mesh_edit("quad", quad);
    mesh.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    auto engine = test::make_engine();
    Material plain;
    plain.base_color = Vec3(0.5f, 0.4f, 0.3f);
    plain.emission = Vec3(0.1f, 0.0f, 0.05f);
    AddMaterial white{"white", plain}, red{"red", plain}, unlit{"unlit", plain};
    white.textures[slot_index(TextureSlot::BaseColor)] = "white-texel";
    white.textures[slot_index(TextureSlot::Emissive)] = "white-texel";
    red.textures[slot_index(TextureSlot::BaseColor)] = "red-texel";
    unlit.material.unlit = true;
    std::vector<Edit> edits = {mesh,
                               AddTexture{"white-texel", test::png_bytes(1, 1, {255, 255, 255})},
                               AddTexture{"red-texel", test::png_bytes(1, 1, {255, 0, 0})},
                               AddMaterial{"plain", plain}, white, red, unlit};
    const char* materials[] = {"plain", "white", "red", "unlit"};
    for (int k = 0; k < 4; ++k) {
        AddInstance i = instance_edit(materials[k], "quad", Vec3(float(k) * 3.0f - 4.5f, 0, 0));
        i.material = materials[k];
        edits.emplace_back(std::move(i));
    }
    edits.emplace_back(SetCamera{Vec3(0, 12, 0.01f), Vec3(0), Vec3(0, 0, -1), 60.0f});
    const FrameBuffers f = primary_frame(*engine, std::move(edits), 64, 32);
    const std::vector<uint32_t> ids =
        instance_slots(*engine, {materials[0], materials[1], materials[2], materials[3]});
    std::vector<Vec3> colour(4, Vec3(-1.0f));
    for (std::size_t p = 0; p < f.pixel_count(); ++p)
        for (int k = 0; k < 4; ++k)
            if (f.instance_id[p] == ids[std::size_t(k)]) colour[std::size_t(k)] = f.color[p];
    for (int k = 0; k < 4; ++k) ASSERT_GE(colour[std::size_t(k)].x, 0.0f) << materials[k];
    EXPECT_LT(glm::length(colour[1] - colour[0]), 1e-5f) << "a white texel changes nothing";
    EXPECT_NEAR(colour[2].x, colour[0].x, 1e-5f) << "red keeps the red channel";
    EXPECT_LT(colour[2].y, colour[0].y - 0.01f) << "and drops the others";
    EXPECT_NEAR(colour[2].y, plain.emission.y, 1e-5f);
    EXPECT_LT(glm::length(colour[3] - plain.base_color), 1e-6f) << "unlit: the base colour";
    EXPECT_GT(colour[0].x, plain.base_color.x * 0.1f + plain.emission.x) << "lit by sun and sky";
}

TEST(RenderKnownAnswer, ThePrimaryPassGivesEveryPixelItsOwnInstancesNormalAndShade) {
    // Rotated, unevenly scaled spheres close together, lit and unlit, in an image whose edges
    // cut packets and tiles: packets see one instance, several, or none, and every pixel must
    // get its own instance's normal (the inverse transpose of its transform) and the preview
    // formula over exactly that normal.
    auto engine = test::make_engine();
    Material matte;
    matte.base_color = Vec3(0.7f, 0.5f, 0.3f);
    matte.emission = Vec3(0.05f, 0.0f, 0.02f);
    Material glow = matte;
    glow.unlit = true;
    SetLighting light;
    light.sun_direction = Vec3(0.3f, 0.9f, 0.5f);
    light.sun_color = Vec3(1.0f, 0.9f, 0.8f);
    light.sky_color = Vec3(0.2f, 0.3f, 0.6f);
    light.sky_intensity = 0.5f;
    std::vector<Edit> edits = {mesh_edit("ball", make_sphere(1.0f, 48)),
                               AddMaterial{"matte", matte}, AddMaterial{"glow", glow}, light};
    std::vector<Affine> transforms;
    for (int k = 0; k < 12; ++k) {
        const Vec3 at(float(k % 4) * 2.3f - 3.45f, float(k / 4) * 1.9f - 1.9f, 0.0f);
        const Affine t = Affine::trs(at, Affine::rotation_euler_deg(Vec3(20.0f * k, 35.0f, 10.0f)),
                                     Vec3(1.25f, 0.7f, 0.9f));
        AddInstance i = instance_edit("i" + std::to_string(k), "ball");
        i.transform = t;
        i.material = k % 3 == 2 ? "glow" : "matte";
        edits.emplace_back(std::move(i));
        transforms.push_back(t);
    }
    Camera camera;
    camera.eye = Vec3(0.3f, 0.2f, 11.0f);
    edits.emplace_back(SetCamera{camera.eye, camera.target, camera.up, camera.fov_y_deg});
    constexpr uint32_t WIDTH = 61, HEIGHT = 37;
    const FrameBuffers f = primary_frame(*engine, std::move(edits), WIDTH, HEIGHT);
    std::vector<std::string> names;
    for (int k = 0; k < 12; ++k) names.push_back("i" + std::to_string(k));
    const std::vector<uint32_t> slots = instance_slots(*engine, names);
    const Vec3 sky = *light.sky_color * *light.sky_intensity;
    const Vec3 sun = glm::normalize(*light.sun_direction);
    const CameraRays rays(camera, WIDTH, HEIGHT);
    std::vector<int> hits(12, 0);
    for (uint32_t y = 0; y < HEIGHT; ++y) {
        for (uint32_t x = 0; x < WIDTH; ++x) {
            const std::size_t p = std::size_t(y) * WIDTH + x;
            const Vec3 n = f.normal[p], colour = f.color[p];
            if (f.instance_id[p] == INVALID_ID) {
                EXPECT_EQ(f.depth[p], std::numeric_limits<float>::infinity()) << x << "," << y;
                EXPECT_EQ(f.primitive_id[p], INVALID_ID);
                EXPECT_EQ(n, Vec3(0.0f));
                EXPECT_EQ(colour, sky);
                continue;
            }
            const auto k = std::size_t(std::find(slots.begin(), slots.end(), f.instance_id[p]) -
                                       slots.begin());
            ASSERT_LT(k, slots.size()) << "pixel " << x << "," << y;
            ++hits[k];
            // The sphere's own normal at the hit, taken to world space.
            const Vec3 dir = rays.direction(float(x) + 0.5f, float(y) + 0.5f);
            const Vec3 hit = transforms[k].inverse().transform_point(camera.eye + dir * f.depth[p]);
            const Vec3 expected =
                glm::normalize(transforms[k].normal_matrix() * glm::normalize(hit));
            EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
            EXPECT_GT(glm::dot(n, expected), 0.97f) << "pixel " << x << "," << y;
            EXPECT_LE(glm::dot(n, dir), 0.0f) << "faces the camera";
            const Vec3 lit =
                matte.base_color * (*light.sun_color * std::max(0.0f, glm::dot(n, sun)) + sky) +
                matte.emission;
            const Vec3 want = k % 3 == 2 ? glow.base_color : lit;
            for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(colour[c], want[c]) << x << "," << y;
        }
    }
    for (int k = 0; k < 12; ++k) EXPECT_GT(hits[std::size_t(k)], 20) << "instance " << k;
}

}  // namespace
}  // namespace strata

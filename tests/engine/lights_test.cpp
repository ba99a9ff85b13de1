// Point, spot and rect lights and emitting meshes: the rules of the light ops, their least work,
// their journal and snapshot form, and known answers for the light they deliver.
//
// The known answers compare a light with the sun (shading.h: a sun of colour c delivers
// irradiance pi * c), straight above a grey floor seen through a narrow camera: a point light of
// intensity I at height h delivers I / h^2, a small rect light or emitting quad of radiance L and
// area A facing the floor about L * A / h^2. With the sky and the other lights off, the floor must
// then look the same as under a sun of colour E / pi from straight above.

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/scene/shapes.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using test::instance_edit;
using test::mesh_edit;
using test::point_light;

constexpr float PI = std::numbers::pi_v<float>;
constexpr float HEIGHT = 2.0f;

/// A floor with sky and sun off, seen at 45 degrees through a 2-degree camera.
EditBatch dark_floor() {
    EditBatch b;
    b.edits.emplace_back(mesh_edit("floor", make_plane(Vec3(40.0f, 0.0f, 40.0f), 1, 1)));
    AddMaterial grey{"grey", {}};
    grey.material.base_color = Vec3(0.5f);
    grey.material.roughness = 1.0f;
    b.edits.emplace_back(grey);
    AddInstance floor = instance_edit("floor", "floor");
    floor.material = "grey";
    b.edits.emplace_back(floor);
    SetLighting off;
    off.sun_color = Vec3(0.0f);
    off.sky_intensity = 0.0f;
    b.edits.emplace_back(off);
    Camera cam;
    cam.eye = Vec3(0.0f, 6.0f, 6.0f);
    cam.target = Vec3(0.0f);
    cam.fov_y_deg = 2.0f;
    b.edits.emplace_back(test::camera_edit(cam));
    return b;
}

/// The mean colour of a small frame of the floor's centre.
Vec3 mean_floor_colour(Engine& engine, uint32_t spp) {
    const Frame f = test::render_frame_ok(engine, test::request(9, 9, spp));
    Vec3 sum(0.0f);
    for (const Vec3& c : f.buffers.color) sum += c;
    return f.buffers.color.empty() ? Vec3(0.0f) : sum / float(f.buffers.color.size());
}

/// The same floor under a sun from straight above delivering irradiance `irradiance`.
Vec3 floor_under_sun(float irradiance) {
    auto engine = test::engine_with(dark_floor());
    SetLighting sun;
    sun.sun_direction = Vec3(0.0f, 1.0f, 0.0f);
    sun.sun_color = Vec3(irradiance / PI);
    apply_ok(*engine, sun);
    return mean_floor_colour(*engine, 16);
}

void expect_close(const Vec3& got, const Vec3& want, float relative) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], relative * want[k]) << "channel " << k;
}

// Step: rules ------------------------------------------------------------------------------------

TEST(Lights, AddUpdateAndRemoveKeepTheirValuesAndIds) {
    auto engine = test::make_engine();
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(1, 2, 3), 5.0f)});
    UpdateLight u;
    u.light = "lamp";
    u.kind = LightKind::Spot;
    u.angle_deg = 40.0f;
    apply_ok(*engine, u);
    engine->read([](const Scene& s) {
        const LightRecord* r = s.lights().get(s.find_light("lamp"));
        ASSERT_NE(r, nullptr);
        EXPECT_EQ(r->light.kind, LightKind::Spot);
        EXPECT_EQ(r->light.position, Vec3(1, 2, 3));
        EXPECT_EQ(r->light.intensity, 5.0f);
        EXPECT_EQ(r->light.angle_deg, 40.0f);
        EXPECT_EQ(s.counts().lights, 1u);
    });
    apply_ok(*engine, RemoveLight{"lamp"});
    engine->read([](const Scene& s) { EXPECT_TRUE(s.find_light("lamp").is_null()); });
}

struct BadLight {
    const char* name;
    void (*spoil)(Light&);
    const char* field;
};

class LightRules : public ::testing::TestWithParam<BadLight> {};

TEST_P(LightRules, AnInvalidLightIsRefusedNamingTheFieldAndChangesNothing) {
    auto engine = test::make_engine();
    Light l = point_light(Vec3(0, 3, 0), 10.0f);
    GetParam().spoil(l);
    EditBatch b;
    b.edits.emplace_back(AddLight{"ok", point_light(Vec3(0), 1.0f)});
    b.edits.emplace_back(AddLight{"bad", l});
    auto r = engine->apply(std::move(b));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, GetParam().field) << r.error().describe();
    EXPECT_EQ(r.error().edit_index, 1u);
    engine->read([](const Scene& s) {
        EXPECT_EQ(s.lights().size(), 0u);
        EXPECT_EQ(s.version(), 0u);
    });
}

INSTANTIATE_TEST_SUITE_P(
    Fields, LightRules,
    ::testing::Values(
        BadLight{"NanPosition", [](Light& l) { l.position.x = std::nanf(""); }, "position"},
        BadLight{"FarPosition", [](Light& l) { l.position.y = 1e20f; }, "position"},
        BadLight{"ZeroDirection", [](Light& l) { l.direction = Vec3(0.0f); }, "direction"},
        BadLight{"NegativeColor", [](Light& l) { l.color.z = -1.0f; }, "color"},
        BadLight{"InfiniteIntensity", [](Light& l) { l.intensity = INFINITY; }, "intensity"},
        BadLight{"NegativeIntensity", [](Light& l) { l.intensity = -1.0f; }, "intensity"},
        BadLight{"WideCone", [](Light& l) { l.angle_deg = 91.0f; }, "angle_deg"},
        BadLight{"InnerPastOuter", [](Light& l) { l.inner_angle_deg = 45.0f; }, "inner_angle_deg"},
        BadLight{"ZeroWidth", [](Light& l) { l.width = 0.0f; }, "width"},
        BadLight{"HugeHeight", [](Light& l) { l.height = 1e7f; }, "height"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Lights, UnknownAndDuplicateIdsAreRefused) {
    auto engine = test::make_engine();
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(0), 1.0f)});
    auto dup = engine->apply(EditBatch{{AddLight{"lamp", point_light(Vec3(0), 1.0f)}}});
    ASSERT_FALSE(dup.has_value());
    EXPECT_EQ(dup.error().code, ErrorCode::DuplicateId);
    UpdateLight u;
    u.light = "nope";
    auto unknown = engine->apply(EditBatch{{u}});
    ASSERT_FALSE(unknown.has_value());
    EXPECT_EQ(unknown.error().code, ErrorCode::UnknownId);
    EXPECT_EQ(unknown.error().field, "light");
    auto gone = engine->apply(EditBatch{{RemoveLight{"nope"}}});
    ASSERT_FALSE(gone.has_value());
    EXPECT_EQ(gone.error().code, ErrorCode::UnknownId);
}

TEST(Lights, AnUpdateThatWouldMakeTheLightInvalidIsRefused) {
    auto engine = test::make_engine();
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(0), 1.0f)});
    UpdateLight u;
    u.light = "lamp";
    u.inner_angle_deg = 60.0f;  // past the default 30-degree cone
    auto r = engine->apply(EditBatch{{u}});
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, "inner_angle_deg");
}

TEST(Lights, ARefusedBatchTakesBackItsLightEdits) {
    auto engine = test::make_engine();
    apply_ok(*engine, AddLight{"a", point_light(Vec3(0), 1.0f)},
             AddLight{"b", point_light(Vec3(1), 2.0f)});
    UpdateLight u;
    u.light = "a";
    u.intensity = 7.0f;
    EditBatch b;
    b.edits.emplace_back(u);
    b.edits.emplace_back(RemoveLight{"b"});
    b.edits.emplace_back(AddLight{"c", point_light(Vec3(2), 3.0f)});
    b.edits.emplace_back(Clear{});
    b.edits.emplace_back(RemoveLight{"missing"});
    ASSERT_FALSE(engine->apply(std::move(b)).has_value());
    engine->read([](const Scene& s) {
        ASSERT_EQ(s.lights().size(), 2u);
        EXPECT_EQ(s.lights().get(s.find_light("a"))->light.intensity, 1.0f);
        EXPECT_EQ(s.lights().get(s.find_light("b"))->light.intensity, 2.0f);
        EXPECT_TRUE(s.find_light("c").is_null());
    });
}

TEST(Lights, ClearRemovesThem) {
    auto engine = test::make_engine();
    apply_ok(*engine, AddLight{"a", point_light(Vec3(0), 1.0f)});
    apply_ok(*engine, Clear{});
    engine->read([](const Scene& s) { EXPECT_EQ(s.lights().size(), 0u); });
}

// Step: least work
// ---------------------------------------------------------------------------------

TEST(Lights, LightEditsRebuildNothing) {
    auto engine = test::engine_with(dark_floor());
    commit_ok(*engine);
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(0, 2, 0), 5.0f)});
    RebuildReport r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    UpdateLight u;
    u.light = "lamp";
    u.position = Vec3(1, 3, 0);
    apply_ok(*engine, u);
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    apply_ok(*engine, RemoveLight{"lamp"});
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_action, TlasAction::None);
}

// Step: journal and snapshot ----------------------------------------------------------------------

TEST(Lights, LightEditsRoundTripThroughTheJournalCodec) {
    Light rect;
    rect.kind = LightKind::Rect;
    rect.position = Vec3(1, 2, 3);
    rect.direction = Vec3(0, -1, 0.5f);
    rect.color = Vec3(1, 0.5f, 0.25f);
    rect.intensity = 12.0f;
    rect.width = 2.0f;
    rect.height = 0.5f;
    UpdateLight u;
    u.light = "r";
    u.kind = LightKind::Spot;
    u.inner_angle_deg = 3.0f;
    EditBatch in;
    in.edits.emplace_back(AddLight{"r", rect});
    in.edits.emplace_back(u);
    in.edits.emplace_back(RemoveLight{"r"});
    std::string bytes;
    durable::encode_batch(in, bytes);
    auto out = durable::decode_batch(bytes);
    ASSERT_TRUE(out.has_value()) << out.error().describe();
    ASSERT_EQ(out.value().edits.size(), 3u);
    const auto& add = std::get<AddLight>(out.value().edits[0]);
    EXPECT_EQ(add.id, "r");
    EXPECT_EQ(add.light, rect);
    const auto& upd = std::get<UpdateLight>(out.value().edits[1]);
    EXPECT_EQ(upd.kind, LightKind::Spot);
    EXPECT_EQ(upd.inner_angle_deg, 3.0f);
    EXPECT_FALSE(upd.position.has_value());
    EXPECT_EQ(std::get<RemoveLight>(out.value().edits[2]).light, "r");
}

TEST(Lights, AnOutOfRangeLightKindInAJournalIsRefused) {
    EditBatch in;
    in.edits.emplace_back(AddLight{"x", point_light(Vec3(0), 1.0f)});
    std::string bytes;
    durable::encode_batch(in, bytes);
    // count (4), tag (1), id length (4) + "x": the kind byte follows.
    bytes[4 + 1 + 4 + 1] = 3;
    EXPECT_FALSE(durable::decode_batch(bytes).has_value());
}

TEST(Lights, TheSceneImageRebuildsTheLights) {
    Scene scene;
    Light spot = point_light(Vec3(0, 4, 0), 3.0f);
    spot.kind = LightKind::Spot;
    ASSERT_TRUE(scene.apply(EditBatch{{AddLight{"s", spot}}}).has_value());
    Scene copy;
    ASSERT_TRUE(copy.apply(scene.image().to_batch()).has_value());
    const LightRecord* r = copy.lights().get(copy.find_light("s"));
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->light, spot);
}

// Step: known answers
// ------------------------------------------------------------------------------

TEST(LightsRender, WithNoLightTheDarkFloorIsBlack) {
    auto engine = test::engine_with(dark_floor());
    const Vec3 c = mean_floor_colour(*engine, 4);
    EXPECT_EQ(c, Vec3(0.0f));
}

TEST(LightsRender, APointLightDeliversIntensityOverDistanceSquared) {
    auto engine = test::engine_with(dark_floor());
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(0, HEIGHT, 0), 8.0f)});
    const Vec3 lit = mean_floor_colour(*engine, 16);
    expect_close(lit, floor_under_sun(8.0f / (HEIGHT * HEIGHT)), 0.02f);
    EXPECT_GT(lit.x, 0.0f);
}

TEST(LightsRender, ASpotLightLightsInsideItsConeOnly) {
    auto engine = test::engine_with(dark_floor());
    Light spot = point_light(Vec3(0, HEIGHT, 0), 8.0f);
    spot.kind = LightKind::Spot;
    spot.angle_deg = 20.0f;
    spot.inner_angle_deg = 10.0f;
    apply_ok(*engine, AddLight{"spot", spot});
    expect_close(mean_floor_colour(*engine, 16), floor_under_sun(8.0f / (HEIGHT * HEIGHT)), 0.02f);
    // Aimed 45 degrees away, the cone misses the floor's centre.
    UpdateLight away;
    away.light = "spot";
    away.direction = Vec3(1, -1, 0);
    apply_ok(*engine, away);
    EXPECT_EQ(mean_floor_colour(*engine, 4), Vec3(0.0f));
}

TEST(LightsRender, ARectLightDeliversRadianceTimesAreaOverDistanceSquared) {
    auto engine = test::engine_with(dark_floor());
    Light rect;
    rect.kind = LightKind::Rect;
    rect.position = Vec3(0, HEIGHT, 0);
    rect.direction = Vec3(0, -1, 0);
    rect.width = rect.height = 0.1f;
    rect.intensity = 400.0f;
    apply_ok(*engine, AddLight{"panel", rect});
    const float irradiance = 400.0f * 0.01f / (HEIGHT * HEIGHT);
    expect_close(mean_floor_colour(*engine, 64), floor_under_sun(irradiance), 0.03f);
    // Its back lights nothing.
    UpdateLight flip;
    flip.light = "panel";
    flip.direction = Vec3(0, 1, 0);
    apply_ok(*engine, flip);
    EXPECT_EQ(mean_floor_colour(*engine, 4), Vec3(0.0f));
}

/// The dark floor with a small emitting quad of radiance `emission` at HEIGHT above its centre.
std::unique_ptr<Engine> floor_with_emitter(float emission) {
    auto engine = test::engine_with(dark_floor());
    AddMaterial glow{"glow", {}};
    glow.material.base_color = Vec3(0.0f);
    glow.material.emission = Vec3(emission);
    apply_ok(*engine, mesh_edit("quad", make_plane(Vec3(0.1f, 0.0f, 0.1f), 1, 1)), glow);
    AddInstance quad = instance_edit("quad", "quad", Vec3(0, HEIGHT, 0));
    quad.material = "glow";
    apply_ok(*engine, quad);
    return engine;
}

TEST(LightsRender, AnEmittingMeshLightsTheFloorAsARectLightOfItsSizeWould) {
    auto engine = floor_with_emitter(400.0f);
    const float irradiance = 400.0f * 0.01f / (HEIGHT * HEIGHT);
    // Both strategies (light sampling and bounce rays reaching the quad) weighted by MIS: the
    // mean is the irradiance, whichever found it.
    expect_close(mean_floor_colour(*engine, 256), floor_under_sun(irradiance), 0.04f);
}

TEST(LightsRender, TheEmitterTableFollowsMaterialAndTransformEdits) {
    auto engine = floor_with_emitter(400.0f);
    const Vec3 near = mean_floor_colour(*engine, 16);
    UpdateInstance up;
    up.instance = "quad";
    up.transform = Affine::translation(Vec3(0, 2.0f * HEIGHT, 0));
    apply_ok(*engine, up);
    const Vec3 far = mean_floor_colour(*engine, 16);
    // Twice as high: a quarter of the light.
    EXPECT_NEAR(far.x, 0.25f * near.x, 0.06f * near.x);
    UpdateMaterial off;
    off.material = "glow";
    off.emission = Vec3(0.0f);
    apply_ok(*engine, off);
    EXPECT_EQ(mean_floor_colour(*engine, 4), Vec3(0.0f));
}

TEST(LightsRender, LightSamplingIsReproducible) {
    // Frames stay reproducible: light sampling draws from the pixel's own sequence.
    auto engine = floor_with_emitter(100.0f);
    apply_ok(*engine, AddLight{"lamp", point_light(Vec3(1, HEIGHT, 0), 3.0f)});
    const Frame a = test::render_frame_ok(*engine, test::request(16, 16, 4));
    const Frame b = test::render_frame_ok(*engine, test::request(16, 16, 4));
    EXPECT_EQ(a.buffers.color, b.buffers.color);
}

}  // namespace
}  // namespace strata

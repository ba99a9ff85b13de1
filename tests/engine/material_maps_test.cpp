// glTF 2.0's material maps: textures decoded as colour or data with their alpha, the five texture
// slots of a material (rules, undo, journal), generated tangents, and what each map does to a
// frame: normal maps bend the shading normal, metallic-roughness and emissive textures multiply
// their factors, occlusion darkens light from bounces, unlit shows the base colour, and the mask
// and blend alpha modes let rays through (closest hits, shadow rays and picks, under both TLAS
// strategies).

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/image/texture_decode.h"
#include "engine/render/tangents.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using ::testing::HasSubstr;

/// An 8-bit RGBA PNG of `w` x `h` pixels.
std::string rgba_png(uint32_t w, uint32_t h, const std::vector<uint8_t>& rgba) {
    auto png = encode_png(rgba.data(), w, h, 4);
    EXPECT_TRUE(png.has_value());
    return png.has_value() ? png.value() : std::string();
}

/// A 1x1 PNG of one colour.
std::string pixel_png(uint8_t r, uint8_t g, uint8_t b) {
    return test::png_bytes(1, 1, {r, g, b});
}

AddTexture texture(const std::string& id, std::string bytes,
                   TextureColorSpace space = TextureColorSpace::Srgb) {
    AddTexture t{id, std::move(bytes)};
    t.color_space = space;
    return t;
}

void expect_near(const Vec3& got, const Vec3& want, float tol = 1e-3f) {
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}

// Step: decoding ---------------------------------------------------------------------------------

TEST(MaterialMapsDecode, ALinearTextureKeepsItsCodesAndAnSrgbOneIsDecoded) {
    const std::string png = test::png_bytes(1, 1, {128, 0, 255});
    auto lin = decode_texture(png, {}, TextureColorSpace::Linear);
    auto srgb = decode_texture(png, {}, TextureColorSpace::Srgb);
    ASSERT_TRUE(lin.has_value() && srgb.has_value());
    expect_near(lin->texel(0, 0), Vec3(128.0f / 255.0f, 0.0f, 1.0f), 1e-4f);
    expect_near(srgb->texel(0, 0), Vec3(0.2158605f, 0.0f, 1.0f), 1e-4f);
    // JPEG too.
    auto jpeg = decode_texture(test::jpeg_bytes(8, 8, 128, 128, 128), {}, TextureColorSpace::Linear);
    ASSERT_TRUE(jpeg.has_value());
    EXPECT_NEAR(jpeg->texel(3, 3).x, 128.0f / 255.0f, 0.02f);
}

TEST(MaterialMapsDecode, APngKeepsItsAlphaUnlessEveryTexelIsOpaque) {
    auto cut = decode_texture(rgba_png(2, 1, {255, 0, 0, 0, 0, 255, 0, 255}), {});
    ASSERT_TRUE(cut.has_value());
    ASSERT_EQ(cut->alpha.size(), 2u);
    EXPECT_EQ(cut->alpha[0], 0);
    EXPECT_EQ(cut->alpha[1], 255);
    EXPECT_EQ(cut->bytes(), 2u * TEXTURE_BYTES_PER_TEXEL + 2u * TEXTURE_BYTES_PER_ALPHA);
    const TextureSampler nearest{TextureWrap::Clamp, TextureFilter::Nearest};
    EXPECT_EQ(cut->sample_alpha({0.25f, 0.5f}, nearest), 0.0f);
    EXPECT_EQ(cut->sample_alpha({0.75f, 0.5f}, nearest), 1.0f);
    EXPECT_NEAR(cut->sample_alpha({0.5f, 0.5f}, {TextureWrap::Clamp, TextureFilter::Bilinear}),
                0.5f, 1e-3f);

    auto opaque = decode_texture(rgba_png(2, 1, {1, 2, 3, 255, 4, 5, 6, 255}), {});
    ASSERT_TRUE(opaque.has_value());
    EXPECT_TRUE(opaque->alpha.empty());
    EXPECT_EQ(opaque->sample_alpha({0.5f, 0.5f}, nearest), 1.0f);
}

TEST(MaterialMapsDecode, AnImageThatMayHaveAlphaIsRefusedFromItsHeaderCountingIt) {
    // 4x4 RGBA: 16 texels of 6 + 1 bytes; a budget of 6 bytes a texel is one byte a texel short.
    TextureLimits limits;
    limits.max_bytes = 16 * TEXTURE_BYTES_PER_TEXEL;
    auto r = decode_texture(rgba_png(4, 4, std::vector<uint8_t>(64, 7)), limits);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_TRUE(decode_texture(test::png_bytes(4, 4, std::vector<uint8_t>(48, 7)), limits));
}

// Step: tangents ---------------------------------------------------------------------------------

TEST(MaterialMapsTangents, TangentsFollowUAndTheBitangentPointsWhereVFalls) {
    // A quad facing +z, u to the right and v down the image (glTF), so up in the world.
    const std::vector<Vec3> p = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {1, 1, 0}};
    const std::vector<Triangle> t = {{0, 1, 2}, {1, 3, 2}};
    const std::vector<Vec3> n(4, Vec3(0, 0, 1));
    const std::vector<Vec2> uv = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
    for (const glm::vec4& tan : make_tangents(p, t, n, uv)) {
        expect_near(Vec3(tan), Vec3(1, 0, 0));
        EXPECT_EQ(tan.w, 1.0f);  // cross(n, t) = +y: up, where v falls
    }
    // Mirrored in u: the tangent turns round and the handedness flips.
    const std::vector<Vec2> mirrored = {{1, 1}, {0, 1}, {1, 0}, {0, 0}};
    for (const glm::vec4& tan : make_tangents(p, t, n, mirrored)) {
        expect_near(Vec3(tan), Vec3(-1, 0, 0));
        EXPECT_EQ(tan.w, -1.0f);
    }
    // No uv area: any tangent orthogonal to the normal.
    const std::vector<Vec2> flat(4, Vec2(0.5f));
    for (const glm::vec4& tan : make_tangents(p, t, n, flat)) {
        EXPECT_NEAR(glm::dot(Vec3(tan), Vec3(0, 0, 1)), 0.0f, 1e-6f);
        EXPECT_NEAR(glm::length(Vec3(tan)), 1.0f, 1e-5f);
    }
}

// Step: rules, undo and the journal --------------------------------------------------------------

TEST(MaterialMapsRules, EachSlotNamesAnExistingTextureAndTheErrorNamesTheSlot) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture("n", pixel_png(128, 128, 255), TextureColorSpace::Linear));
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        AddMaterial m{"m-" + std::string(slot.field), Material{}};
        m.textures[slot_index(slot.slot)] = "missing";
        EditBatch b;
        b.edits.emplace_back(m);
        auto r = engine->apply(std::move(b));
        ASSERT_FALSE(r.has_value());
        EXPECT_EQ(r.error().code, ErrorCode::UnknownId);
        EXPECT_EQ(r.error().field, slot.field);
    }
    AddMaterial all{"all", Material{}};
    for (auto& t : all.textures) t = "n";
    apply_ok(*engine, all);
    // Removing the texture is refused while any slot names it.
    UpdateMaterial drop{"all"};
    for (std::size_t s = 0; s + 1 < TEXTURE_SLOT_COUNT; ++s) drop.textures[s].emplace();
    apply_ok(*engine, drop);
    EditBatch remove;
    remove.edits.emplace_back(RemoveTexture{"n"});
    auto refused = engine->apply(std::move(remove));
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().code, ErrorCode::InUse);
    drop = UpdateMaterial{"all"};
    drop.textures[slot_index(TextureSlot::Emissive)].emplace();
    apply_ok(*engine, drop, RemoveTexture{"n"});
}

TEST(MaterialMapsRules, UndoBringsBackEverySlotAndField) {
    auto engine = test::make_engine();
    AddMaterial m{"m", Material{}};
    m.material.alpha_mode = AlphaMode::Mask;
    m.material.alpha_cutoff = 0.25f;
    m.textures[slot_index(TextureSlot::Normal)] = "n";
    const uint64_t before = apply_ok(
        *engine, texture("n", pixel_png(128, 128, 255), TextureColorSpace::Linear),
        texture("e", pixel_png(255, 0, 0)), m);
    UpdateMaterial u{"m"};
    u.textures[slot_index(TextureSlot::Normal)].emplace();
    u.textures[slot_index(TextureSlot::Emissive)] = std::optional<std::string>("e");
    u.alpha_mode = AlphaMode::Blend;
    u.unlit = true;
    u.normal_scale = 2.0f;
    const uint64_t after = apply_ok(*engine, u);
    auto undo = engine->undo_batch(after);
    ASSERT_TRUE(undo.has_value()) << undo.error().describe();
    ASSERT_TRUE(engine->apply(std::move(undo).value(), after).has_value());
    engine->read([&](const Scene& s) {
        const MaterialRecord* r = s.material(s.find_material("m")).value();
        EXPECT_EQ(r->textures[slot_index(TextureSlot::Normal)], s.find_texture("n"));
        EXPECT_TRUE(r->textures[slot_index(TextureSlot::Emissive)].is_null());
        EXPECT_EQ(r->material.alpha_mode, AlphaMode::Mask);
        EXPECT_EQ(r->material.alpha_cutoff, 0.25f);
        EXPECT_FALSE(r->material.unlit);
        EXPECT_EQ(r->material.normal_scale, 1.0f);
        EXPECT_EQ(s.texture(s.find_texture("n")).value()->color_space, TextureColorSpace::Linear);
    });
    EXPECT_GT(after, before);
}

TEST(MaterialMapsCodec, SlotsFieldsAndColourSpacesRoundTripAndOldLayoutsReadTheSame) {
    EditBatch b;
    b.edits.emplace_back(texture("n", pixel_png(128, 128, 255), TextureColorSpace::Linear));
    AddMaterial m{"m", Material{}};
    m.material.alpha = 0.5f;
    m.material.alpha_mode = AlphaMode::Blend;
    m.material.alpha_cutoff = 0.1f;
    m.material.normal_scale = -1.5f;
    m.material.occlusion_strength = 0.75f;
    m.material.unlit = true;
    for (auto& t : m.textures) t = "n";
    b.edits.emplace_back(m);
    UpdateMaterial u{"m"};
    u.textures[slot_index(TextureSlot::Occlusion)].emplace();  // none
    u.textures[slot_index(TextureSlot::Emissive)] = std::optional<std::string>("n");
    u.alpha_mode = AlphaMode::Mask;
    b.edits.emplace_back(u);
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    const auto& t = std::get<AddTexture>(back->edits[0]);
    EXPECT_EQ(t.color_space, TextureColorSpace::Linear);
    const auto& am = std::get<AddMaterial>(back->edits[1]);
    EXPECT_EQ(am.material, m.material);
    EXPECT_EQ(am.textures, m.textures);
    const auto& um = std::get<UpdateMaterial>(back->edits[2]);
    EXPECT_EQ(um.textures, u.textures);
    EXPECT_EQ(um.alpha_mode, std::optional(AlphaMode::Mask));
    std::string again;
    durable::encode_batch(*back, again);
    EXPECT_EQ(again, bytes);

    // A material with a base-colour texture only is written in the first extension layout,
    // byte for byte as before the slots existed: no tagged section.
    EditBatch plain;
    AddMaterial base{"b", Material{}};
    base.textures[slot_index(TextureSlot::BaseColor)] = "n";
    plain.edits.emplace_back(base);
    std::string plain_bytes;
    durable::encode_batch(plain, plain_bytes);
    EXPECT_EQ(uint8_t(plain_bytes[4]) & 0x40, 0);
}

TEST(MaterialMapsLeastWork, MapAndAlphaEditsTouchNoBvh) {
    auto engine = test::make_engine();
    apply_ok(*engine, test::mesh_edit("tri", MeshData{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}}),
             AddMaterial{"m", Material{}}, test::instance_edit("i", "tri"),
             texture("n", pixel_png(128, 128, 255), TextureColorSpace::Linear));
    commit_ok(*engine);
    UpdateMaterial u{"m"};
    u.textures[slot_index(TextureSlot::Normal)] = std::optional<std::string>("n");
    u.alpha_mode = AlphaMode::Mask;
    u.unlit = true;
    apply_ok(*engine, u);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
}

// Step: frames -----------------------------------------------------------------------------------

/// A 2x2 quad facing +z at depth z with normals and uvs ((0, 0) at its top-left corner).
AddMesh quad_mesh(const std::string& id, float z = 0.0f) {
    AddMesh quad;
    quad.id = id;
    quad.positions = {{-1, -1, z}, {1, -1, z}, {-1, 1, z}, {1, 1, z}};
    quad.triangles = {{0, 1, 2}, {1, 3, 2}};
    quad.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    quad.uvs = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
    return quad;
}

SetCamera straight_on() {
    SetCamera cam;
    cam.eye = Vec3(0, 0, 3);
    cam.target = Vec3(0, 0, 0);
    cam.up = Vec3(0, 1, 0);
    cam.fov_y_deg = 30.0f;  // the quad fills the frame
    return cam;
}

/// The quad mesh (with `tangents`, when given) in front of the camera; the caller adds material
/// "m" and quad_instance().
std::unique_ptr<Engine> quad_scene(EngineConfig config = {}, std::vector<Vec4> tangents = {}) {
    auto engine = test::create_engine(config);
    EXPECT_TRUE(engine.has_value());
    AddMesh quad = quad_mesh("quad");
    quad.tangents = std::move(tangents);
    apply_ok(**engine, quad, straight_on());
    return std::move(engine).value();
}

/// The instance "q" of the quad with material "m".
AddInstance quad_instance() {
    AddInstance inst = test::instance_edit("q", "quad");
    inst.material = "m";
    return inst;
}

/// The centre pixel of a 16x16 render with `aovs`.
Frame centre_frame(Engine& engine, std::vector<Aov> aovs, uint32_t spp = 1) {
    return test::render_frame_ok(engine, test::request(16, 16, spp, std::move(aovs)));
}
constexpr std::size_t CENTRE = 8 * 16 + 8;

Vec3 shading_normal_with_map(uint8_t r, uint8_t g, uint8_t b, float scale = 1.0f,
                             std::vector<Vec4> tangents = {}) {
    auto engine = quad_scene({}, std::move(tangents));
    AddMaterial m{"m", Material{}};
    m.material.normal_scale = scale;
    m.textures[slot_index(TextureSlot::Normal)] = "n";
    AddInstance inst = quad_instance();
    apply_ok(*engine, texture("n", pixel_png(r, g, b), TextureColorSpace::Linear), m, inst);
    return centre_frame(*engine, {Aov::Normal}).buffers.normal[CENTRE];
}

TEST(MaterialMapsRender, ANormalMapBendsTheShadingNormalWithPlusYUpTheImage) {
    expect_near(shading_normal_with_map(128, 128, 255), Vec3(0, 0, 1), 0.01f);
    // Green up: toward the top of the image, +y in the world (bitangent = cross(n, t)).
    const Vec3 up = shading_normal_with_map(128, 218, 218);
    EXPECT_GT(up.y, 0.5f);
    EXPECT_NEAR(up.x, 0.0f, 0.02f);
    const Vec3 down = shading_normal_with_map(128, 38, 218);
    EXPECT_LT(down.y, -0.5f);
    // Red right: +x, where u grows.
    EXPECT_GT(shading_normal_with_map(218, 128, 218).x, 0.5f);
    // normal_scale 0 flattens the map; a negative one mirrors it.
    expect_near(shading_normal_with_map(128, 218, 218, 0.0f), Vec3(0, 0, 1), 0.01f);
    EXPECT_LT(shading_normal_with_map(128, 218, 218, -1.0f).y, -0.5f);
}

TEST(MaterialMapsRender, AMeshsOwnTangentsOrientTheNormalMap) {
    // The quad's generated tangents are +x (where u grows) with w = 1: given as its own, the
    // frame is the same.
    const std::vector<Vec4> generated(4, Vec4(1, 0, 0, 1));
    expect_near(shading_normal_with_map(218, 128, 218, 1.0f, generated),
                shading_normal_with_map(218, 128, 218), 1e-5f);
    // Tangents along +y: red (the tangent) now bends the normal up, and green, along
    // cross(n, t) = -x, to the left.
    const std::vector<Vec4> up(4, Vec4(0, 1, 0, 1));
    const Vec3 red = shading_normal_with_map(218, 128, 218, 1.0f, up);
    EXPECT_GT(red.y, 0.5f);
    EXPECT_NEAR(red.x, 0.0f, 0.02f);
    EXPECT_LT(shading_normal_with_map(128, 218, 218, 1.0f, up).x, -0.5f);
    // w = -1 mirrors the bitangent: green bends the normal down where the made tangents bend it
    // up.
    const std::vector<Vec4> mirrored(4, Vec4(1, 0, 0, -1));
    EXPECT_LT(shading_normal_with_map(128, 218, 218, 1.0f, mirrored).y, -0.5f);
}

TEST(MaterialMapsRender, UnlitShowsTheTexturedBaseColourExactly) {
    auto engine = quad_scene();
    AddMaterial m{"m", Material{}};
    m.material.base_color = Vec3(0.5f, 1.0f, 1.0f);
    m.material.unlit = true;
    m.textures[slot_index(TextureSlot::BaseColor)] = "c";
    AddInstance inst = quad_instance();
    apply_ok(*engine, texture("c", pixel_png(255, 255, 0)), m, inst);
    const Frame f = centre_frame(*engine, {Aov::Albedo}, 4);
    expect_near(f.buffers.color[CENTRE], Vec3(0.5f, 1.0f, 0.0f), 1e-5f);
    expect_near(f.buffers.albedo[CENTRE], Vec3(0.5f, 1.0f, 0.0f), 1e-5f);
}

/// The centre colour of the unlit quad whose base-colour texture (red left, blue right) reads
/// set `set`, the mesh's uvs pointing at the red texel and its uvs1 (when given) at the blue one.
Vec3 colour_through_uv_set(uint32_t set, bool with_uvs1) {
    auto engine = test::create_engine();
    EXPECT_TRUE(engine.has_value());
    AddMesh quad = quad_mesh("quad");
    quad.uvs = std::vector<Vec2>(4, Vec2(0.25f, 0.5f));
    if (with_uvs1) quad.uvs1 = std::vector<Vec2>(4, Vec2(0.75f, 0.5f));
    AddMaterial m{"m", Material{}};
    m.material.base_color = Vec3(1.0f);
    m.material.unlit = true;
    m.material.base_color_sampler.filter = TextureFilter::Nearest;
    m.material.base_color_uv_set = set;
    m.textures[slot_index(TextureSlot::BaseColor)] = "c";
    apply_ok(**engine, quad, straight_on(),
             texture("c", rgba_png(2, 1, {255, 0, 0, 255, 0, 0, 255, 255})), m, quad_instance());
    return centre_frame(**engine, {}).buffers.color[CENTRE];
}

TEST(MaterialMapsRender, EachSlotReadsTheTextureCoordinateSetItNames) {
    expect_near(colour_through_uv_set(0, true), Vec3(1, 0, 0), 1e-5f);
    expect_near(colour_through_uv_set(1, true), Vec3(0, 0, 1), 1e-5f);
    // A mesh without the second set reads its first there.
    expect_near(colour_through_uv_set(1, false), Vec3(1, 0, 0), 1e-5f);
}

TEST(MaterialMapsRules, AUvSetIsZeroOrOneAndItsUpdateTouchesNoBvh) {
    auto engine = quad_scene();
    AddMaterial m{"m", Material{}};
    m.material.occlusion_uv_set = 2;
    EditBatch bad;
    bad.edits.emplace_back(m);
    auto refused = engine->apply(std::move(bad));
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().field, "occlusion_uv_set");
    EXPECT_NE(refused.error().message.find("[0, 1]"), std::string::npos)
        << refused.error().message;
    m.material.occlusion_uv_set = 1;
    apply_ok(*engine, m, quad_instance());
    test::commit_ok(*engine);
    UpdateMaterial u;
    u.material = "m";
    u.occlusion_uv_set = 0;
    apply_ok(*engine, u);
    EXPECT_TRUE(test::commit_ok(*engine).no_accel_work());
    engine->read([](const Scene& s) {
        EXPECT_EQ(s.material(s.find_material("m")).value()->material.occlusion_uv_set, 0u);
    });
}

TEST(MaterialMapsRender, MetallicRoughnessEmissiveAndOcclusionTexturesMultiplyTheirFactors) {
    auto engine = quad_scene();
    AddMaterial m{"m", Material{}};
    m.material.roughness = 0.8f;
    m.material.metallic = 1.0f;
    m.material.emission = Vec3(2.0f);
    m.material.occlusion_strength = 0.5f;
    m.textures[slot_index(TextureSlot::MetallicRoughness)] = "mr";
    m.textures[slot_index(TextureSlot::Emissive)] = "e";
    m.textures[slot_index(TextureSlot::Occlusion)] = "ao";
    AddInstance inst = quad_instance();
    apply_ok(*engine, texture("mr", pixel_png(0, 128, 64), TextureColorSpace::Linear),
             texture("e", pixel_png(255, 0, 0)),
             texture("ao", pixel_png(0, 255, 255), TextureColorSpace::Linear), m, inst);
    commit_ok(*engine);
    engine->launch([](const FrameState& frame, const TlasStrategy&, const RebuildReport&) {
        const uint32_t index = frame.instances[0].material;
        const SurfaceMaterial s = frame.surface(index, frame.mesh_shade(0), 0, 0.3f, 0.3f);
        EXPECT_NEAR(s.material.roughness, 0.8f * 128.0f / 255.0f, 1e-4f);
        EXPECT_NEAR(s.material.metallic, 64.0f / 255.0f, 1e-4f);
        expect_near(s.material.emission, Vec3(2.0f, 0.0f, 0.0f), 1e-4f);
        EXPECT_NEAR(s.occlusion, 0.5f, 1e-4f);  // 1 + 0.5 * (0 - 1)
        // The light table sees the emitter as its factor times the texture's mean.
        expect_near(frame.emitter_emission[index], Vec3(2.0f, 0.0f, 0.0f), 1e-4f);
        return 0;
    });
}

TEST(MaterialMapsRender, OcclusionDarkensOnlyTheLightThatArrivesByBounces) {
    auto render = [](float strength) {
        auto engine = quad_scene();
        AddMaterial m{"m", Material{}};
        m.material.occlusion_strength = strength;
        m.textures[slot_index(TextureSlot::Occlusion)] = "ao";
        AddInstance inst = quad_instance();
        SetLighting sky_only;
        sky_only.sun_color = Vec3(0.0f);
        apply_ok(*engine, texture("ao", pixel_png(0, 0, 0), TextureColorSpace::Linear), m, inst,
                 sky_only);
        return luminance(centre_frame(*engine, {}, 16).buffers.color[CENTRE]);
    };
    const float open = render(0.0f);
    EXPECT_GT(open, 0.05f);
    EXPECT_EQ(render(1.0f), 0.0f);  // fully occluded: the sky is its only light
    EXPECT_NEAR(render(0.5f), 0.5f * open, 0.1f * open);
}

/// What a launch config names: a TLAS strategy, and whether edits go to a dynamic tier.
struct TlasCase {
    const char* name;
    TlasKind kind;
    uint32_t min_instances;

    friend void PrintTo(const TlasCase& c, std::ostream* os) { *os << c.name; }
};

class CoverageRender : public ::testing::TestWithParam<TlasCase> {
protected:
    EngineConfig config() const {
        EngineConfig c;
        c.accel.tlas = GetParam().kind;
        c.accel.tlas_policy.min_instances = GetParam().min_instances;
        c.accel.tlas_policy.background_merge = false;
        if (GetParam().min_instances == 0) c.accel.tlas_policy.max_dynamic_fraction = 1.0;
        return c;
    }

    /// A red opaque quad at z = -0.5 behind the quad "q" (material "m", added by the test),
    /// committed first so that "q" lands in the dynamic tier where the strategy keeps one.
    std::unique_ptr<Engine> scene_behind() const {
        auto engine = quad_scene(config());
        AddMaterial red{"red", Material{}};
        red.material.base_color = Vec3(1, 0, 0);
        AddInstance back = test::instance_edit("back", "quad");
        back.material = "red";
        back.transform = Affine::translation(Vec3(0, 0, -0.5f));
        apply_ok(*engine, red, back);
        commit_ok(*engine);
        return engine;
    }
};

TEST_P(CoverageRender, AMaskCutsThroughWhereAlphaIsBelowTheCutoffForFramesAndPicks) {
    auto engine = scene_behind();
    // Left half transparent, right half opaque; white.
    AddMaterial m{"m", Material{}};
    m.material.base_color = Vec3(1.0f);
    m.material.alpha_mode = AlphaMode::Mask;
    m.material.base_color_sampler.filter = TextureFilter::Nearest;
    m.textures[slot_index(TextureSlot::BaseColor)] = "a";
    AddInstance inst = quad_instance();
    apply_ok(*engine, texture("a", rgba_png(2, 1, {255, 255, 255, 0, 255, 255, 255, 255})), m,
             inst);
    const RebuildReport r = commit_ok(*engine);
    if (GetParam().min_instances == 0) EXPECT_GE(r.tlas.dynamic_instances, 1u);  // "q" is there
    const Frame f = test::render_frame_ok(*engine, test::request(16, 16, 1, {Aov::Albedo}));
    expect_near(f.buffers.albedo[8 * 16 + 3], Vec3(1, 0, 0));  // through the hole: red
    expect_near(f.buffers.albedo[8 * 16 + 12], Vec3(1, 1, 1));
    PickRequest pick{16, 16, {{3, 8}, {12, 8}}};
    auto picked = engine->pick(pick);
    ASSERT_TRUE(picked.has_value());
    ASSERT_TRUE(picked->hits[0] && picked->hits[1]);
    EXPECT_EQ(picked->hits[0]->instance, "back");
    EXPECT_EQ(picked->hits[1]->instance, "q");
    // Raising the cutoff above 1 - nothing is that covered - cuts the whole quad away.
    UpdateMaterial all{"m"};
    all.alpha_cutoff = 1.0f;
    all.alpha = 0.99f;
    apply_ok(*engine, all);
    const Frame g = test::render_frame_ok(*engine, test::request(16, 16, 1, {Aov::Albedo}));
    expect_near(g.buffers.albedo[8 * 16 + 12], Vec3(1, 0, 0));
}

TEST_P(CoverageRender, AFullyCutAwayInstanceLeavesTheFrameAsItWasWithoutIt) {
    auto engine = scene_behind();
    SetLighting l;
    l.sun_direction = Vec3(0.3f, 0.2f, 1.0f);  // the front quad would shadow the back one
    apply_ok(*engine, l);
    const Frame without = test::render_frame_ok(*engine, test::request(24, 24, 4));
    AddMaterial m{"m", Material{}};
    m.material.alpha_mode = AlphaMode::Mask;
    m.material.alpha = 0.0f;
    AddInstance inst = quad_instance();
    inst.transform = Affine::translation(Vec3(0, 0, 0.25f));
    apply_ok(*engine, m, inst);
    const Frame with = test::render_frame_ok(*engine, test::request(24, 24, 4));
    EXPECT_EQ(with.buffers.color, without.buffers.color);
    // Opaque again: it shows (and shades) again.
    UpdateMaterial opaque{"m"};
    opaque.alpha_mode = AlphaMode::Opaque;
    apply_ok(*engine, opaque);
    const Frame shown = test::render_frame_ok(*engine, test::request(24, 24, 4));
    EXPECT_NE(shown.buffers.color, without.buffers.color);
}

TEST_P(CoverageRender, BlendLetsRaysThroughInProportionToAlpha) {
    auto engine = scene_behind();
    AddMaterial m{"m", Material{}};
    m.material.base_color = Vec3(0, 0, 1);
    m.material.alpha_mode = AlphaMode::Blend;
    m.material.alpha = 0.25f;
    AddInstance inst = quad_instance();
    apply_ok(*engine, m, inst);
    const Frame f = test::render_frame_ok(*engine, test::request(16, 16, 256, {Aov::Albedo}));
    // Over many samples the albedo is alpha * front + (1 - alpha) * back.
    double red = 0.0, blue = 0.0;
    for (const Vec3& a : f.buffers.albedo) {
        red += a.x;
        blue += a.z;
    }
    const double n = double(f.buffers.albedo.size());
    EXPECT_NEAR(blue / n, 0.25, 0.03);
    EXPECT_NEAR(red / n, 0.75, 0.03);
}

INSTANTIATE_TEST_SUITE_P(
    Strategies, CoverageRender,
    ::testing::Values(TlasCase{"incremental_static", TlasKind::Incremental, 1024},
                      TlasCase{"incremental_dynamic", TlasKind::Incremental, 0},
                      TlasCase{"embree", TlasKind::Embree, 1024}),
    [](const ::testing::TestParamInfo<TlasCase>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace strata

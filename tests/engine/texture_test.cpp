// Textures: decoding untrusted PNG and JPEG bytes (sRGB to linear, limits read from the header,
// corrupt files named), lookups (wrap modes, filters), the scene's rules for add_texture,
// remove_texture and a material's base_color_texture (in use, rollback, clear, budget), their
// journal encoding, the least work they cause, and a textured render.

#include <string>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/image/texture_decode.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using ::testing::HasSubstr;

TextureImage decode_ok(const std::string& bytes, const TextureLimits& limits = {}) {
    auto r = decode_texture(bytes, limits);
    EXPECT_TRUE(r.has_value()) << (r ? "" : r.error().describe());
    return r ? std::move(r.value()) : TextureImage{};
}

Error decode_refused(const std::string& bytes, const TextureLimits& limits = {}) {
    auto r = decode_texture(bytes, limits);
    EXPECT_FALSE(r.has_value());
    return r ? Error{} : r.error();
}

void expect_near(const Vec3& got, const Vec3& want, float tol = 1e-3f) {
    EXPECT_NEAR(got.x, want.x, tol);
    EXPECT_NEAR(got.y, want.y, tol);
    EXPECT_NEAR(got.z, want.z, tol);
}

// Step: decoding ---------------------------------------------------------------------------------

TEST(TextureDecode, APngDecodesToLinearRgbThroughTheSrgbCurve) {
    // 128 in sRGB is 0.2158605 linear; 255 is 1 and 0 is 0.
    const TextureImage t = decode_ok(test::png_bytes(2, 1, {128, 0, 255, 255, 255, 255}));
    ASSERT_EQ(t.width, 2u);
    ASSERT_EQ(t.height, 1u);
    expect_near(t.texel(0, 0), Vec3(0.2158605f, 0.0f, 1.0f), 1e-4f);
    expect_near(t.texel(1, 0), Vec3(1.0f));
    EXPECT_EQ(t.bytes(), 2u * TEXTURE_BYTES_PER_TEXEL);
    EXPECT_EQ(srgb8_to_linear16(0), 0);
    EXPECT_EQ(srgb8_to_linear16(255), 65535);
}

TEST(TextureDecode, AJpegDecodesToLinearRgb) {
    const TextureImage t = decode_ok(test::jpeg_bytes(16, 8, 255, 128, 0));
    ASSERT_EQ(t.width, 16u);
    ASSERT_EQ(t.height, 8u);
    // JPEG is lossy: within a few codes of the source, through the sRGB curve.
    expect_near(t.texel(5, 3), Vec3(1.0f, 0.2158605f, 0.0f), 0.02f);
}

TEST(TextureDecode, BytesThatAreNeitherPngNorJpegAreRefusedNamingTheCause) {
    Error e = decode_refused("GIF89a....");
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field, "data");
    EXPECT_THAT(e.message, HasSubstr("neither PNG nor JPEG"));
    e = decode_refused("");
    EXPECT_THAT(e.message, HasSubstr("empty"));
}

TEST(TextureDecode, TruncatedOrDamagedFilesAreRefusedWithTheDecodersReason) {
    const std::string png = test::four_colour_png();
    Error e = decode_refused(png.substr(0, png.size() / 2));
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_THAT(e.message, HasSubstr("corrupt PNG"));

    std::string bad_crc = png;
    bad_crc[20] ^= 0x01;  // inside IHDR: its CRC no longer matches
    e = decode_refused(bad_crc);
    EXPECT_THAT(e.message, HasSubstr("corrupt PNG"));

    const std::string jpeg = test::jpeg_bytes(32, 32, 10, 20, 30);
    e = decode_refused(jpeg.substr(0, jpeg.size() / 2));
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_THAT(e.message, HasSubstr("corrupt JPEG"));
    e = decode_refused(jpeg.substr(0, 40));
    EXPECT_THAT(e.message, HasSubstr("corrupt JPEG"));
}

TEST(TextureDecode, AHugeImageIsRefusedFromItsHeaderBeforeItsTexelsAreAllocated) {
    // 100000 x 100000 would be 60 GB decoded; the data behind the header is one pixel.
    Error e = decode_refused(test::png_claiming(100000, 100000));
    EXPECT_EQ(e.code, ErrorCode::TooLarge);
    EXPECT_EQ(e.field, "data");
    EXPECT_THAT(e.message, HasSubstr("100000x100000"));
    // Within the side limit but over the bytes left in the budget.
    TextureLimits small;
    small.max_bytes = 1000;
    e = decode_refused(test::png_claiming(100, 100), small);
    EXPECT_EQ(e.code, ErrorCode::TooLarge);
    EXPECT_THAT(e.message, HasSubstr("max_texture_mb"));
    e = decode_refused(test::jpeg_bytes(64, 64, 1, 2, 3), small);
    EXPECT_EQ(e.code, ErrorCode::TooLarge);
}

// Step: lookups ----------------------------------------------------------------------------------

TextureImage four_colours() {
    return decode_ok(test::four_colour_png());
}

TEST(TextureLookup, NearestReadsTheTexelUnderTheCoordinateWithVDownward) {
    const TextureImage t = four_colours();
    const TextureSampler nearest{TextureWrap::Repeat, TextureFilter::Nearest};
    expect_near(t.sample({0.25f, 0.25f}, nearest), Vec3(1, 0, 0));
    expect_near(t.sample({0.75f, 0.25f}, nearest), Vec3(0, 1, 0));
    expect_near(t.sample({0.25f, 0.75f}, nearest), Vec3(0, 0, 1));
    expect_near(t.sample({0.75f, 0.75f}, nearest), Vec3(1, 1, 1));
}

TEST(TextureLookup, BilinearBlendsTheFourNearestTexelCentres) {
    const TextureImage t = four_colours();
    const TextureSampler clamp{TextureWrap::Clamp, TextureFilter::Bilinear};
    expect_near(t.sample({0.25f, 0.25f}, clamp), Vec3(1, 0, 0));          // a texel centre
    expect_near(t.sample({0.5f, 0.5f}, clamp), Vec3(0.5f, 0.5f, 0.5f));   // all four, equally
    expect_near(t.sample({0.5f, 0.25f}, clamp), Vec3(0.5f, 0.5f, 0.0f));  // red and green
    // Clamp: beyond the edge is the edge texel.
    expect_near(t.sample({-3.0f, 0.25f}, clamp), Vec3(1, 0, 0));
}

TEST(TextureLookup, RepeatClampAndMirrorWrapOutsideTheUnitSquare) {
    const TextureImage t = four_colours();
    auto at = [&](float u, TextureWrap w) {
        return t.sample({u, 0.25f}, TextureSampler{w, TextureFilter::Nearest});
    };
    // u = 1.25: repeat is 0.25 (red), clamp the last column (green), mirror 0.75 (green).
    expect_near(at(1.25f, TextureWrap::Repeat), Vec3(1, 0, 0));
    expect_near(at(1.25f, TextureWrap::Clamp), Vec3(0, 1, 0));
    expect_near(at(1.25f, TextureWrap::Mirror), Vec3(0, 1, 0));
    // u = 1.75: repeat 0.75 (green), mirror 0.25 (red).
    expect_near(at(1.75f, TextureWrap::Repeat), Vec3(0, 1, 0));
    expect_near(at(1.75f, TextureWrap::Mirror), Vec3(1, 0, 0));
    // Negative: repeat -0.25 is 0.75 (green); mirror -0.25 is 0.25 (red).
    expect_near(at(-0.25f, TextureWrap::Repeat), Vec3(0, 1, 0));
    expect_near(at(-0.25f, TextureWrap::Mirror), Vec3(1, 0, 0));
    // Far coordinates stay finite.
    const Vec3 far = t.sample({3e38f, -3e38f}, TextureSampler{});
    EXPECT_TRUE(is_finite(far));
}

// Step: the scene's rules ------------------------------------------------------------------------

AddTexture texture_edit(const std::string& id, std::string bytes = test::four_colour_png()) {
    return AddTexture{id, std::move(bytes)};
}

AddMaterial textured_material(const std::string& id, const std::string& texture) {
    AddMaterial m{id, Material{}};
    m.material.base_color = Vec3(1.0f);
    m.textures[0] = texture;
    return m;
}

Error refused(Engine& engine, EditBatch b) {
    auto r = engine.apply(std::move(b));
    EXPECT_FALSE(r.has_value());
    return r ? Error{} : r.error();
}

template <class... E>
EditBatch batch(E&&... e) {
    EditBatch b;
    (b.edits.emplace_back(std::forward<E>(e)), ...);
    return b;
}

TEST(TextureRules, AMaterialNamesATextureThatExists) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture_edit("checker"), textured_material("m", "checker"));
    engine->read([](const Scene& s) {
        const TextureRecord* t = s.texture(s.find_texture("checker")).value();
        EXPECT_EQ(t->image->width, 2u);
        const MaterialRecord* m = s.material(s.find_material("m")).value();
        EXPECT_EQ(m->textures[0], s.find_texture("checker"));
        EXPECT_EQ(s.mesh_totals().texture_bytes,
                  4u * TEXTURE_BYTES_PER_TEXEL + test::four_colour_png().size());
        EXPECT_EQ(s.counts().textures, 1u);
    });
    const Error e = refused(*engine, batch(textured_material("m2", "nope")));
    EXPECT_EQ(e.code, ErrorCode::UnknownId);
    EXPECT_EQ(e.field, "base_color_texture");
}

TEST(TextureRules, ACorruptImageIsRefusedNamingTheTextureAndChangesNothing) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture_edit("good"));
    const std::string png = test::four_colour_png();
    const Error e =
        refused(*engine, batch(texture_edit("ok"), texture_edit("bad", png.substr(0, 30))));
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_EQ(e.edit_index, 1u);
    EXPECT_EQ(e.field, "data");
    EXPECT_THAT(e.message, HasSubstr("texture 'bad'"));
    EXPECT_THAT(e.message, HasSubstr("corrupt PNG"));
    engine->read([](const Scene& s) {
        EXPECT_TRUE(s.find_texture("ok").is_null());
        EXPECT_EQ(s.textures().size(), 1u);
        EXPECT_EQ(s.mesh_totals().texture_bytes,
                  4u * TEXTURE_BYTES_PER_TEXEL + test::four_colour_png().size());
    });
}

TEST(TextureRules, ATextureInUseCannotBeRemovedUntilNoMaterialNamesIt) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture_edit("t"), textured_material("a", "t"), textured_material("b", "t"));
    Error e = refused(*engine, batch(RemoveTexture{"t"}));
    EXPECT_EQ(e.code, ErrorCode::InUse);
    EXPECT_EQ(e.field, "texture");
    EXPECT_THAT(e.message, HasSubstr("2 material(s)"));

    UpdateMaterial drop_a;
    drop_a.material = "a";
    drop_a.textures[0] = std::optional<std::string>();
    UpdateMaterial drop_b = drop_a;
    drop_b.material = "b";
    e = refused(*engine, batch(drop_a, RemoveTexture{"t"}));  // b still uses it
    EXPECT_EQ(e.code, ErrorCode::InUse);
    engine->read([](const Scene& s) {  // and the batch's first edit was undone
        EXPECT_FALSE(s.material(s.find_material("a")).value()->textures[0].is_null());
    });
    apply_ok(*engine, drop_a, drop_b, RemoveTexture{"t"});
    engine->read([](const Scene& s) {
        EXPECT_TRUE(s.find_texture("t").is_null());
        EXPECT_EQ(s.mesh_totals().texture_bytes, 0u);
    });
    e = refused(*engine, batch(RemoveTexture{"t"}));
    EXPECT_EQ(e.code, ErrorCode::UnknownId);
}

TEST(TextureRules, ARefusedBatchRestoresRemovedTexturesAndMaterialBindings) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture_edit("t"), texture_edit("u"), textured_material("m", "t"));
    const std::string before = engine->read([](const Scene& s) {
        std::string out;
        durable::encode_batch(s.to_batch(), out);
        return out;
    });
    UpdateMaterial swap;
    swap.material = "m";
    swap.textures[0] = std::optional<std::string>("u");
    swap.wrap = TextureWrap::Mirror;
    const Error e =
        refused(*engine, batch(swap, RemoveTexture{"t"}, texture_edit("v"), RemoveMesh{"missing"}));
    EXPECT_EQ(e.edit_index, 3u);
    const std::string after = engine->read([](const Scene& s) {
        std::string out;
        durable::encode_batch(s.to_batch(), out);
        return out;
    });
    EXPECT_EQ(after, before);
}

TEST(TextureRules, ClearRemovesTexturesToo) {
    auto engine = test::make_engine();
    apply_ok(*engine, texture_edit("t"), textured_material("m", "t"));
    apply_ok(*engine, Clear{});
    engine->read([](const Scene& s) {
        EXPECT_EQ(s.textures().size(), 0u);
        EXPECT_EQ(s.mesh_totals().texture_bytes, 0u);
    });
    apply_ok(*engine, texture_edit("t"));  // the id is free again
}

TEST(TextureRules, TexturesCountAgainstTheTextureBudget) {
    // A texture costs its texels (4 of 6 bytes: 24) and its file: four fit, a fifth does not.
    const uint64_t one = 4 * TEXTURE_BYTES_PER_TEXEL + test::four_colour_png().size();
    EngineConfig config;
    config.budget.max_texture_bytes = 4 * one + one / 2;
    auto engine = std::move(test::create_engine(config).value());
    apply_ok(*engine, texture_edit("a"), texture_edit("b"), texture_edit("c"), texture_edit("d"));
    const Error e = refused(*engine, batch(texture_edit("e")));
    EXPECT_EQ(e.code, ErrorCode::TooLarge);
    EXPECT_EQ(e.field, "data");
    EXPECT_THAT(e.message, HasSubstr("max_texture_mb"));
    apply_ok(*engine, RemoveTexture{"a"}, texture_edit("e"));
}

// Step: journal encoding and least work ----------------------------------------------------------

TEST(TextureCodec, TextureEditsAndMaterialBindingsRoundTripThroughTheJournalEncoding) {
    AddMaterial add = textured_material("m", "t");
    add.material.base_color_sampler = {TextureWrap::Mirror, TextureFilter::Nearest};
    UpdateMaterial unbind;
    unbind.material = "m";
    unbind.textures[0] = std::optional<std::string>();
    unbind.filter = TextureFilter::Bilinear;
    UpdateMaterial untouched;
    untouched.material = "m";
    untouched.roughness = 0.25f;
    const EditBatch b = batch(texture_edit("t"), add, unbind, untouched, RemoveTexture{"t"},
                              AddMaterial{"plain", Material{}});
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    ASSERT_EQ(back->edits.size(), b.edits.size());
    const auto& t = std::get<AddTexture>(back->edits[0]);
    EXPECT_EQ(t.id, "t");
    EXPECT_EQ(t.data, test::four_colour_png());
    const auto& m = std::get<AddMaterial>(back->edits[1]);
    EXPECT_EQ(m.textures[0], std::optional<std::string>("t"));
    EXPECT_EQ(m.material, add.material);
    const auto& u = std::get<UpdateMaterial>(back->edits[2]);
    ASSERT_TRUE(u.textures[0].has_value());
    EXPECT_FALSE(u.textures[0]->has_value());
    EXPECT_EQ(u.filter, std::optional<TextureFilter>(TextureFilter::Bilinear));
    EXPECT_FALSE(u.wrap.has_value());
    const auto& v = std::get<UpdateMaterial>(back->edits[3]);
    EXPECT_FALSE(v.textures[0].has_value());
    EXPECT_EQ(std::get<RemoveTexture>(back->edits[4]).texture, "t");
    EXPECT_FALSE(std::get<AddMaterial>(back->edits[5]).textures[0].has_value());
    // A wrap byte past the last mode is corruption, not a mode.
    std::string one;
    durable::encode_batch(batch(add), one);
    one[one.size() - 2] = 3;
    EXPECT_FALSE(durable::decode_batch(one).has_value());
}

TEST(TextureLeastWork, TextureAndTextureBindingEditsTouchNoBvh) {
    auto engine = test::make_engine();
    AddMesh quad = test::mesh_edit("quad", make_plane(Vec3(2.0f), 1, 1));
    quad.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    apply_ok(*engine, quad, AddMaterial{"m", Material{}}, test::instance_edit("q", "quad"));
    commit_ok(*engine);
    UpdateMaterial bind;
    bind.material = "m";
    bind.textures[0] = std::optional<std::string>("t");
    bind.wrap = TextureWrap::Clamp;
    apply_ok(*engine, texture_edit("t"), bind);
    RebuildReport r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    bind.textures[0] = std::optional<std::string>();
    apply_ok(*engine, bind, RemoveTexture{"t"});
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
}

// Step: rendering --------------------------------------------------------------------------------

/// A 2x2 quad facing +z at z = 0 with uvs (0, 0) at its top-left corner, a white material with the
/// four-colour texture, and a camera looking at it straight on.
std::unique_ptr<Engine> textured_quad_scene(TextureFilter filter) {
    auto engine = test::make_engine();
    AddMesh quad;
    quad.id = "quad";
    quad.positions = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}, {1, 1, 0}};
    quad.triangles = {{0, 1, 2}, {1, 3, 2}};
    quad.uvs = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
    AddMaterial m = textured_material("m", "t");
    m.material.base_color_sampler.filter = filter;
    AddInstance inst = test::instance_edit("q", "quad");
    inst.material = "m";
    SetCamera cam;
    cam.eye = Vec3(0, 0, 3);
    cam.target = Vec3(0, 0, 0);
    cam.up = Vec3(0, 1, 0);
    apply_ok(*engine, texture_edit("t"), m, quad, inst, cam);
    return engine;
}

TEST(TextureRender, TheAlbedoOfATexturedQuadShowsEachTexelInItsQuadrant) {
    auto engine = textured_quad_scene(TextureFilter::Nearest);
    const uint32_t W = 64, H = 64;
    const Frame f = test::render_frame_ok(*engine, test::request(W, H, 4, {Aov::Albedo}));
    const Camera cam = engine->read([](const Scene& s) { return s.camera(); });
    auto albedo_at = [&](Vec3 p) {
        const glm::vec2 px = test::project(cam, W, H, p);
        return f.buffers.albedo[std::size_t(px.y) * W + std::size_t(px.x)];
    };
    expect_near(albedo_at({-0.5f, 0.5f, 0}), Vec3(1, 0, 0));
    expect_near(albedo_at({0.5f, 0.5f, 0}), Vec3(0, 1, 0));
    expect_near(albedo_at({-0.5f, -0.5f, 0}), Vec3(0, 0, 1));
    expect_near(albedo_at({0.5f, -0.5f, 0}), Vec3(1, 1, 1));
    // The colour follows: the red quadrant reflects red light only.
    const glm::vec2 red = test::project(cam, W, H, {-0.5f, 0.5f, 0});
    const Vec3 c = f.buffers.color[std::size_t(red.y) * W + std::size_t(red.x)];
    EXPECT_GT(c.x, 0.05f);
    EXPECT_LT(c.y, 0.2f * c.x);
    EXPECT_LT(c.z, 0.2f * c.x);
}

TEST(TextureRender, UnbindingTheTextureBringsBackThePlainBaseColour) {
    auto engine = textured_quad_scene(TextureFilter::Bilinear);
    UpdateMaterial unbind;
    unbind.material = "m";
    unbind.textures[0] = std::optional<std::string>();
    unbind.base_color = Vec3(0.25f, 0.5f, 0.75f);
    apply_ok(*engine, unbind, RemoveTexture{"t"});
    const Frame f = test::render_frame_ok(*engine, test::request(32, 32, 1, {Aov::Albedo}));
    expect_near(f.buffers.albedo[16 * 32 + 16], Vec3(0.25f, 0.5f, 0.75f));
}

// Step: the image's own bytes -------------------------------------------------------------------

TEST(ImageLength, PngAndJpegEndWhereTheirLastChunkOrMarkerEnds) {
    const std::string png = test::four_colour_png();
    const std::string jpeg = test::jpeg_bytes(4, 4, 200, 100, 50);
    EXPECT_EQ(image_length(png), png.size());
    EXPECT_EQ(image_length(jpeg), jpeg.size());
    EXPECT_EQ(image_length(png + std::string(1000, 'x')), png.size());
    EXPECT_EQ(image_length(jpeg + "\xFF\xD9trailing"), jpeg.size());
    // Truncated, or neither format: no end.
    EXPECT_EQ(image_length(png.substr(0, png.size() - 1)), 0u);
    EXPECT_EQ(image_length(jpeg.substr(0, jpeg.size() - 2)), 0u);
    EXPECT_EQ(image_length("GIF89a"), 0u);
    // An EOI inside a segment (an EXIF thumbnail) is not the image's end.
    const std::string exif = std::string("Exif\0\0\xFF\xD8\xFF\xD9", 10);
    std::string with_thumbnail = jpeg.substr(0, 2) + "\xFF\xE1" + char(0) +
                                 char(exif.size() + 2) + exif + jpeg.substr(2);
    EXPECT_EQ(image_length(with_thumbnail), with_thumbnail.size());
    EXPECT_TRUE(decode_texture(with_thumbnail, {}).has_value());
}

TEST(TextureRules, OnlyTheImagesOwnBytesAreKeptAndTheFileCountsAgainstTheBudget) {
    // 1 MB after IEND used to be kept with every copy of the texture, and uncounted.
    auto engine = test::make_engine();
    const std::string png = test::four_colour_png();
    const std::string jpeg = test::jpeg_bytes(4, 4, 200, 100, 50);
    apply_ok(*engine, texture_edit("p", png + std::string(1 << 20, '\0')),
             texture_edit("j", jpeg + std::string(1 << 20, 'x')));
    engine->read([&](const Scene& s) {
        EXPECT_EQ(*s.texture(s.find_texture("p")).value()->encoded, png);
        EXPECT_EQ(*s.texture(s.find_texture("j")).value()->encoded, jpeg);
        EXPECT_EQ(s.mesh_totals().texture_bytes,
                  (4 + 16) * TEXTURE_BYTES_PER_TEXEL + png.size() + jpeg.size());
    });
    // A file larger than the budget left is refused before its texels are decoded.
    EngineConfig config;
    config.budget.max_texture_bytes = 4 * TEXTURE_BYTES_PER_TEXEL + png.size() - 1;
    auto small = std::move(test::create_engine(config).value());
    const Error e = refused(*small, batch(texture_edit("p", png)));
    EXPECT_EQ(e.code, ErrorCode::TooLarge);
    EXPECT_THAT(e.message, HasSubstr("bytes left in the texture budget"));
}

TEST(TextureRules, AnImageDecodedAheadIsTakenAsItIsAndCheckedAgainstTheBudgetLeft) {
    // Engine::apply decodes outside the scene lock; the rule then uses that image, not `data`.
    Scene scene;
    AddTexture ahead = texture_edit("ahead");
    ahead.decoded = std::make_shared<DecodedTexture>(
        DecodedTexture{decode_texture(test::png_bytes(3, 1, {1, 2, 3, 4, 5, 6, 7, 8, 9}), {})});
    ASSERT_TRUE(scene.apply(batch(std::move(ahead))).has_value());
    EXPECT_EQ(scene.texture(scene.find_texture("ahead")).value()->image->width, 3u);
    // An image decoded with wider limits still meets the budget left when the rule runs.
    // "ahead" costs its 3 texels and its file; "big" brings a file of the same size, so 10
    // bytes are left for its texels.
    const uint64_t file = test::four_colour_png().size();
    SceneBudget budget;
    budget.max_texture_bytes = 3 * TEXTURE_BYTES_PER_TEXEL + 2 * file + 10;
    scene.set_budget(budget);
    AddTexture big = texture_edit("big");
    big.decoded = std::make_shared<DecodedTexture>(DecodedTexture{decode_texture(big.data, {})});
    auto r = scene.apply(batch(std::move(big)));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_THAT(r.error().message, HasSubstr("texture 'big': PNG image is 2x2"));
    EXPECT_THAT(r.error().message, HasSubstr("10 bytes left in the texture budget"));
    // Through the engine, whose apply decodes ahead, the answers are the same as the rule's.
    auto engine = test::make_engine();
    const Error e = refused(*engine, batch(texture_edit("ok"),
                                           texture_edit("bad", test::four_colour_png().substr(0, 30))));
    EXPECT_EQ(e.edit_index, 1u);
    EXPECT_THAT(e.message, HasSubstr("texture 'bad': corrupt PNG"));
}

}  // namespace
}  // namespace strata

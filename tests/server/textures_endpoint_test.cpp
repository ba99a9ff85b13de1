// Textures over real HTTP: add_texture with base64 PNG and JPEG bytes, the material's texture
// slots and alpha fields, the texture documents and listing, and every refusal with its status
// and pointer (a corrupt image named, a huge one refused from its header with 413, a texture in
// use, an unknown slot texture, a bad alpha mode or colour space).

#include <gmock/gmock.h>

#include "engine/image/png.h"
#include "protocol/base64.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

using ::testing::HasSubstr;

std::string png_2x2() {
    const uint8_t rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    return encode_png(rgb, 2, 2, 3).value();
}

Json add_texture(const std::string& id, const std::string& bytes) {
    return {{"op", "add_texture"}, {"id", id}, {"data", protocol::encode_base64(bytes)}};
}

class Textures : public ::testing::Test {
protected:
    TestServer srv;
};

TEST_F(Textures, ATextureIsAddedBoundListedAndRemoved) {
    const Reply r = srv.edits({add_texture("checker", png_2x2()),
                               {{"op", "add_material"},
                                {"id", "m"},
                                {"base_color_texture", "checker"},
                                {"sampler", {{"wrap", "mirror"}, {"filter", "nearest"}}}}});
    ASSERT_EQ(r.status, 200) << r.body;
    const Json t = srv.get("/v1/scene/textures/checker").json();
    EXPECT_EQ(t["width"], 2);
    EXPECT_EQ(t["height"], 2);
    EXPECT_EQ(t["format"], "png");
    EXPECT_EQ(t["decoded_bytes"], 24);
    EXPECT_EQ(t["encoded_bytes"], png_2x2().size());
    const Json m = srv.get("/v1/scene/materials/m").json();
    EXPECT_EQ(m["base_color_texture"], "checker");
    EXPECT_EQ(m["sampler"], (Json{{"wrap", "mirror"}, {"filter", "nearest"}}));
    const Json list = srv.get("/v1/scene/textures").json();
    ASSERT_EQ(list["items"].size(), 1u);
    EXPECT_EQ(list["items"][0]["id"], "checker");
    EXPECT_EQ(srv.get("/v1/scene").json()["counts"]["textures"], 1);

    expect_problem(srv.edits({{{"op", "remove_texture"}, {"texture", "checker"}}}), 422, "in-use",
                   "/edits/0/texture");
    const Reply gone =
        srv.edits({{{"op", "update_material"}, {"material", "m"}, {"base_color_texture", nullptr}},
                   {{"op", "remove_texture"}, {"texture", "checker"}}});
    ASSERT_EQ(gone.status, 200) << gone.body;
    expect_problem(srv.get("/v1/scene/textures/checker"), 404, "not-found");
    EXPECT_EQ(srv.get("/v1/scene/materials/m").json()["base_color_texture"], nullptr);
}

TEST_F(Textures, ACorruptImageIs422NamingTheTextureAndTheDecodersReason) {
    const std::string png = png_2x2();
    const Reply r = srv.edits({add_texture("ok", png), add_texture("broken", png.substr(0, 40))});
    expect_problem(r, 422, "invalid-value", "/edits/1/data");
    EXPECT_THAT(r.json()["detail"].get<std::string>(), HasSubstr("texture 'broken'"));
    EXPECT_THAT(r.json()["detail"].get<std::string>(), HasSubstr("corrupt PNG"));
    expect_problem(srv.edits({add_texture("gif", "GIF89a")}), 422, "invalid-value",
                   "/edits/0/data");
    expect_problem(srv.get("/v1/scene/textures/ok"), 404);  // the batch was refused whole
    expect_problem(
        srv.edits({{{"op", "add_material"}, {"id", "m"}, {"base_color_texture", "nope"}}}), 422,
        "unknown-id", "/edits/0/base_color_texture");
}

TEST_F(Textures, EveryMaterialMapAndAlphaFieldGoesInAndComesBackOut) {
    Json texture = add_texture("n", png_2x2());
    texture["color_space"] = "linear";
    Json material = {{"op", "add_material"}, {"id", "m"}, {"alpha_mode", "mask"},
                     {"alpha_cutoff", 0.25}, {"unlit", true}, {"normal_scale", -2}};
    for (const char* slot : {"base_color_texture", "metallic_roughness_texture", "normal_texture",
                             "occlusion_texture", "emissive_texture"})
        material[slot] = "n";
    const Reply r = srv.edits({texture, material});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(srv.get("/v1/scene/textures/n").json()["color_space"], "linear");
    const Json m = srv.get("/v1/scene/materials/m").json();
    for (const char* slot : {"base_color_texture", "metallic_roughness_texture", "normal_texture",
                             "occlusion_texture", "emissive_texture"})
        EXPECT_EQ(m[slot], "n") << slot;
    EXPECT_EQ(m["alpha_mode"], "mask");
    EXPECT_EQ(m["alpha_cutoff"], 0.25);
    EXPECT_EQ(m["unlit"], true);
    EXPECT_EQ(m["normal_scale"], -2);
    // One slot at a time: null takes it away, the others stay.
    ASSERT_EQ(srv.edits({{{"op", "update_material"}, {"material", "m"}, {"normal_texture", nullptr},
                          {"alpha_mode", "blend"}}})
                  .status,
              200);
    const Json after = srv.get("/v1/scene/materials/m").json();
    EXPECT_EQ(after["normal_texture"], nullptr);
    EXPECT_EQ(after["emissive_texture"], "n");
    EXPECT_EQ(after["alpha_mode"], "blend");
}

TEST_F(Textures, BadMapsAndAlphaValuesAreRefusedNamingTheMemberAndChangeNothing) {
    ASSERT_EQ(srv.edits({add_texture("t", png_2x2())}).status, 200);
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"normal_texture", "nope"}}}),
                   422, "unknown-id", "/edits/0/normal_texture");
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"alpha_mode", "sometimes"}}}),
                   400, "", "/edits/0/alpha_mode");
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"alpha_cutoff", 1.5}}}), 422,
                   "invalid-value", "/edits/0/alpha_cutoff");
    Json bad_space = add_texture("u", png_2x2());
    bad_space["color_space"] = "cmyk";
    expect_problem(srv.edits({bad_space}), 400, "", "/edits/0/color_space");
    // A batch whose last edit is refused adds nothing before it either.
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"emissive_texture", "t"}},
                              {{"op", "update_material"}, {"material", "m"},
                               {"occlusion_texture", "nope"}}}),
                   422, "unknown-id", "/edits/1/occlusion_texture");
    expect_problem(srv.get("/v1/scene/materials/m"), 404);
}

TEST(TexturesBudget, AnImageOverTheTextureBudgetIs413FromItsHeader) {
    EngineConfig engine;
    // One 2x2 texture (24 bytes of texels and its file), not two.
    engine.budget.max_texture_bytes = 24 + png_2x2().size() + 10;
    TestServer srv({}, false, engine);
    ASSERT_EQ(srv.edits({add_texture("a", png_2x2())}).status, 200);
    const Reply r = srv.edits({add_texture("b", png_2x2())});
    expect_problem(r, 413, "too-large", "/edits/0/data");
    EXPECT_THAT(r.json()["detail"].get<std::string>(), HasSubstr("max_texture_mb"));
}

TEST_F(Textures, ATexturedMaterialRendersItsTexels) {
    const Reply r = srv.edits(
        {add_texture("red", encode_png(std::vector<uint8_t>{255, 0, 0}.data(), 1, 1, 3).value()),
         {{"op", "add_material"},
          {"id", "m"},
          {"base_color", {1, 1, 1}},
          {"base_color_texture", "red"}},
         {{"op", "add_mesh"},
          {"id", "quad"},
          {"positions", {-1, -1, 0, 1, -1, 0, -1, 1, 0, 1, 1, 0}},
          {"indices", {0, 1, 2, 1, 3, 2}},
          {"uvs", {0, 1, 1, 1, 0, 0, 1, 0}}},
         {{"op", "add_instance"}, {"id", "q"}, {"mesh", "quad"}, {"material", "m"}},
         {{"op", "set_camera"}, {"eye", {0, 0, 3}}, {"target", {0, 0, 0}}}});
    ASSERT_EQ(r.status, 200) << r.body;
    const Reply img =
        srv.post("/v1/render", Json{{"width", 16}, {"height", 16}, {"spp", 1}, {"format", "png"}});
    ASSERT_EQ(img.status, 200) << img.body.substr(0, 200);
    auto decoded = decode_png(img.body);
    ASSERT_TRUE(decoded.has_value());
    const auto& px = decoded.value().pixels;
    const int ch = decoded.value().channels;
    const std::size_t centre = (8 * 16 + 8) * std::size_t(ch);
    EXPECT_GT(px[centre], 2 * px[centre + 1]) << "the centre pixel is red";
    EXPECT_GT(px[centre], 2 * px[centre + 2]);
}

TEST_F(Textures, AMeshsTangentsAndSecondUvSetGoInAsJsonAndAreListed) {
    const Json quad = {{"op", "add_mesh"},
                       {"id", "quad"},
                       {"positions", {-1, -1, 0, 1, -1, 0, -1, 1, 0, 1, 1, 0}},
                       {"indices", {0, 1, 2, 1, 3, 2}},
                       {"normals", {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}},
                       {"uvs", {0, 1, 1, 1, 0, 0, 1, 0}},
                       {"uvs1", {0, 0, 0, 0, 0, 0, 0, 0}},
                       {"tangents", {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 0.5}}};
    const Reply bad = srv.edits({quad});
    expect_problem(bad, 422, {}, "/edits/0/tangents/15");
    EXPECT_THAT(bad.json()["detail"].get<std::string>(), HasSubstr("+1 or -1"));
    Json good = quad;
    good["tangents"][15] = -1;
    ASSERT_EQ(srv.edits({good}).status, 200);
    EXPECT_EQ(srv.get("/v1/scene/meshes/quad").json()["tangents"], true);
    EXPECT_EQ(srv.get("/v1/scene/meshes/quad").json()["uvs1"], true);
    // A material slot reads set 0 or 1.
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"occlusion_uv_set", 2}}}), 422,
                   {}, "/edits/0/occlusion_uv_set");
    ASSERT_EQ(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"occlusion_uv_set", 1}}}).status,
              200);
    EXPECT_EQ(srv.get("/v1/scene/materials/m").json()["occlusion_uv_set"], 1);
    ASSERT_EQ(srv.edits({{{"op", "update_mesh"}, {"mesh", "quad"}, {"tangents", Json::array()}}})
                  .status,
              200);
    EXPECT_EQ(srv.get("/v1/scene/meshes/quad").json()["tangents"], false);
}

}  // namespace
}  // namespace strata::server::test

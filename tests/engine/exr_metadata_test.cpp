// What an EXR frame says about itself, read back with OpenEXR's own API: the ID manifest that
// names every instance_id and mesh_id pixel with its client id (at the frame's version), the
// standard worldToCamera / worldToNDC matrices, and the user_id AOV.

#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include <ImfHeader.h>
#include <ImfIDManifest.h>
#include <ImfInputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStdIO.h>
#include <gtest/gtest.h>

#include "engine/engine.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::decode_exr_ok;
using test::instance_edit;
using test::mesh_edit;
using test::render_ok;

/// An EXR's header, read by OpenEXR from memory.
Imf::Header read_header(const std::string& bytes) {
    Imf::StdISStream stream;
    stream.str(bytes);
    Imf::InputFile file(stream);
    return file.header();
}

/// id -> text of the manifest's table for `channel` (which must have one component).
std::map<uint64_t, std::string> manifest_table(const Imf::Header& header,
                                               const std::string& channel,
                                               const std::string& component) {
    EXPECT_TRUE(Imf::hasIDManifest(header));
    if (!Imf::hasIDManifest(header)) return {};
    const Imf::IDManifest manifest(Imf::idManifest(header));
    const std::size_t g = manifest.find(channel);
    EXPECT_LT(g, manifest.size()) << "no table for " << channel;
    if (g >= manifest.size()) return {};
    const Imf::IDManifest::ChannelGroupManifest& table = manifest[g];
    EXPECT_EQ(table.getComponents(), std::vector<std::string>{component});
    EXPECT_EQ(table.getEncodingScheme(), Imf::IDManifest::ID_SCHEME);
    EXPECT_EQ(table.getHashScheme(), Imf::IDManifest::NOTHASHED);
    EXPECT_EQ(table.getLifetime(), Imf::IDManifest::LIFETIME_FRAME);
    std::map<uint64_t, std::string> out;
    for (auto it = table.begin(); it != table.end(); ++it) out[it.id()] = it.text().at(0);
    return out;
}

class ExrMetadata : public ::testing::Test {
protected:
    void SetUp() override {
        engine = test::make_engine();
        cam.eye = Vec3(1.0f, 3.0f, 11.0f);
        cam.target = Vec3(0.5f, 0.0f, 0.0f);
        cam.fov_y_deg = 50.0f;
        AddInstance middle = instance_edit("/World/Ball", "ball", Vec3(0.0f));
        middle.user_id = 77;
        AddInstance right = instance_edit("right cube", "cube", Vec3(4.0f, 0.0f, 0.0f));
        right.user_id = 0xFFFFFFFEu;
        apply_ok(*engine, mesh_edit("cube", make_box(Vec3(1.5f))),
                 mesh_edit("ball", make_sphere(0.8f, 48)),
                 mesh_edit("unseen", make_box(Vec3(1.0f))),
                 instance_edit("left", "cube", Vec3(-4.0f, 0.0f, 0.0f)), std::move(middle),
                 std::move(right), instance_edit("behind", "unseen", Vec3(0.0f, 0.0f, 40.0f)),
                 test::camera_edit(cam));
    }

    /// Every id pixel of `exr` resolves through the manifest in `header` to the client id the
    /// scene (at the same version) gives that slot; the manifest names exactly those slots.
    void expect_manifest_names_every_pixel(const Imf::Header& header, const DecodedExr& exr) {
        const auto instances = manifest_table(header, "instance_id", "instance");
        const auto meshes = manifest_table(header, "mesh_id", "mesh");
        const std::vector<uint32_t>& inst = exr.find("instance_id")->u32;
        const std::vector<uint32_t>& mesh = exr.find("mesh_id")->u32;
        std::set<uint64_t> seen_instances, seen_meshes;
        engine->read([&](const Scene& scene) {
            for (std::size_t p = 0; p < inst.size(); ++p) {
                ASSERT_EQ(inst[p] == MISS_ID, mesh[p] == MISS_ID) << "pixel " << p;
                if (inst[p] == MISS_ID) continue;
                seen_instances.insert(inst[p]);
                seen_meshes.insert(mesh[p]);
                ASSERT_TRUE(instances.count(inst[p])) << "pixel " << p << " slot " << inst[p];
                ASSERT_TRUE(meshes.count(mesh[p])) << "pixel " << p << " slot " << mesh[p];
                const std::string& name = instances.at(inst[p]);
                const InstanceHandle h = scene.find_instance(name);
                ASSERT_TRUE(scene.instances().contains(h)) << name;
                EXPECT_EQ(h.index, inst[p]) << name;
                const MeshRecord* m = scene.mesh(scene.instance(h).value()->mesh).value();
                ASSERT_EQ(meshes.at(mesh[p]), m->id) << "pixel " << p;
            }
        });
        std::set<uint64_t> listed_instances, listed_meshes;
        for (const auto& [id, text] : instances) listed_instances.insert(id);
        for (const auto& [id, text] : meshes) listed_meshes.insert(id);
        EXPECT_EQ(listed_instances, seen_instances) << "the manifest names the frame's ids only";
        EXPECT_EQ(listed_meshes, seen_meshes);
    }

    static constexpr uint32_t W = 160, H = 90;
    std::unique_ptr<Engine> engine;
    Camera cam;
};

TEST_F(ExrMetadata, IdManifestResolvesEveryIdPixelToTheClientIdOfTheScene) {
    const std::string bytes =
        render_ok(*engine, test::request(W, H, 1, {Aov::InstanceId, Aov::MeshId})).bytes;
    const Imf::Header header = read_header(bytes);
    const DecodedExr exr = decode_exr_ok(bytes);
    expect_manifest_names_every_pixel(header, exr);
    const auto instances = manifest_table(header, "instance_id", "instance");
    std::set<std::string> names;
    for (const auto& [id, text] : instances) names.insert(text);
    EXPECT_EQ(names, (std::set<std::string>{"left", "/World/Ball", "right cube"}))
        << "'behind' is behind the camera";
}

TEST_F(ExrMetadata, IdManifestNamesTheObjectThatNowHoldsAReusedSlot) {
    const uint32_t old_slot =
        engine->read([](const Scene& s) { return s.find_instance("left").index; });
    RemoveInstance remove;
    remove.instance = "left";
    AddMesh tall = mesh_edit("tall", make_box(Vec3(1.0f, 3.0f, 1.0f)));
    apply_ok(*engine, std::move(remove), std::move(tall),
             instance_edit("newcomer", "tall", Vec3(-4.0f, 0.0f, 0.0f)));
    ASSERT_EQ(engine->read([](const Scene& s) { return s.find_instance("newcomer").index; }),
              old_slot)
        << "the test needs the freed slot to be reused";
    const std::string bytes =
        render_ok(*engine, test::request(W, H, 1, {Aov::InstanceId, Aov::MeshId})).bytes;
    const Imf::Header header = read_header(bytes);
    expect_manifest_names_every_pixel(header, decode_exr_ok(bytes));
    EXPECT_EQ(manifest_table(header, "instance_id", "instance").at(old_slot), "newcomer");
}

TEST_F(ExrMetadata, OnlyTheIdAovsAskedForGetATable) {
    const Imf::Header with_instances =
        read_header(render_ok(*engine, test::request(W, H, 1, {Aov::InstanceId})).bytes);
    const Imf::IDManifest manifest(Imf::idManifest(with_instances));
    EXPECT_EQ(manifest.size(), 1u);
    EXPECT_LT(manifest.find("instance_id"), manifest.size());
    const Imf::Header plain = read_header(render_ok(*engine, test::request(W, H, 1)).bytes);
    EXPECT_FALSE(Imf::hasIDManifest(plain));
    EXPECT_TRUE(Imf::hasWorldToNDC(plain)) << "every EXR frame carries its camera";
}

TEST_F(ExrMetadata, WorldToNdcProjectsEveryHitPointToThePixelCentreItWasSeenThrough) {
    RenderRequest r = test::request(W, H, 1, {Aov::Position, Aov::Depth});
    r.camera = SetCamera{};
    r.camera->fov_y_deg = 35.0f;  // an override: the matrices are those of the traced camera
    const std::string bytes = render_ok(*engine, r).bytes;
    const Imf::Header header = read_header(bytes);
    ASSERT_TRUE(Imf::hasWorldToNDC(header));
    ASSERT_TRUE(Imf::hasWorldToCamera(header));
    const Imath::M44f ndc = Imf::worldToNDC(header);
    const Imath::M44f to_camera = Imf::worldToCamera(header);
    const DecodedExr exr = decode_exr_ok(bytes);
    std::size_t hits = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const std::size_t p = std::size_t(y) * W + x;
            const float depth = exr.find("Z")->f32[p];
            if (!std::isfinite(depth)) continue;
            ++hits;
            const Imath::V3f world(exr.find("P.X")->f32[p], exr.find("P.Y")->f32[p],
                                   exr.find("P.Z")->f32[p]);
            Imath::V3f n;
            ndc.multVecMatrix(world, n);
            ASSERT_NEAR(n.x * W, x + 0.5f, 0.01f) << "pixel " << x << "," << y;
            ASSERT_NEAR(n.y * H, y + 0.5f, 0.01f) << "pixel " << x << "," << y;
            // Camera space is rigid, z along the view, x right and y up in the image.
            Imath::V3f c;
            to_camera.multVecMatrix(world, c);
            ASSERT_NEAR(c.length(), depth, 1e-3f * depth);
            ASSERT_GT(c.z, 0.0f);
            ASSERT_EQ(c.x > 0.0f, x + 0.5f > W / 2.0f) << "pixel " << x << "," << y;
            ASSERT_EQ(c.y > 0.0f, y + 0.5f < H / 2.0f) << "pixel " << x << "," << y;
        }
    }
    EXPECT_GT(hits, 1000u);
}

TEST_F(ExrMetadata, WorldToNdcPutsAKnownPointOnThePixelThatShowsIt) {
    // The ball's centre is hidden inside it, so the pixel it projects to shows the ball.
    const std::string bytes = render_ok(*engine, test::request(W, H, 1, {Aov::InstanceId})).bytes;
    const Imf::Header header = read_header(bytes);
    Imath::V3f n;
    Imf::worldToNDC(header).multVecMatrix(Imath::V3f(0.0f, 0.0f, 0.0f), n);
    ASSERT_GT(n.x, 0.0f);
    ASSERT_LT(n.x, 1.0f);
    ASSERT_GT(n.y, 0.0f);
    ASSERT_LT(n.y, 1.0f);
    const std::size_t p = std::size_t(n.y * H) * W + std::size_t(n.x * W);
    const uint32_t slot = decode_exr_ok(bytes).find("instance_id")->u32[p];
    EXPECT_EQ(manifest_table(header, "instance_id", "instance").at(slot), "/World/Ball");
    const glm::vec2 expected = test::project(cam, W, H, Vec3(0.0f));
    EXPECT_NEAR(n.x * W, expected.x, 1e-3f);
    EXPECT_NEAR(n.y * H, expected.y, 1e-3f);
}

TEST_F(ExrMetadata, UserIdAovCarriesEachInstancesUserIdAndFollowsUpdates) {
    const auto expect_user_ids = [&](const std::map<std::string, uint32_t>& expected) {
        const std::string bytes =
            render_ok(*engine, test::request(W, H, 1, {Aov::InstanceId, Aov::UserId})).bytes;
        const DecodedExr exr = decode_exr_ok(bytes);
        ASSERT_NE(exr.find("user_id"), nullptr);
        EXPECT_EQ(exr.find("user_id")->type, ExrPixel::Uint);
        const auto names = manifest_table(read_header(bytes), "instance_id", "instance");
        std::set<std::string> seen;
        for (std::size_t p = 0; p < std::size_t(W) * H; ++p) {
            const uint32_t slot = exr.find("instance_id")->u32[p];
            const uint32_t user = exr.find("user_id")->u32[p];
            if (slot == MISS_ID) {
                ASSERT_EQ(user, MISS_ID) << "pixel " << p;
                continue;
            }
            const std::string& name = names.at(slot);
            seen.insert(name);
            ASSERT_EQ(user, expected.at(name)) << name;
        }
        EXPECT_EQ(seen.size(), 3u);
    };
    expect_user_ids({{"left", 0u}, {"/World/Ball", 77u}, {"right cube", 0xFFFFFFFEu}});
    UpdateInstance u;
    u.instance = "left";
    u.user_id = 5;
    apply_ok(*engine, std::move(u));
    const RebuildReport report = test::commit_ok(*engine);
    EXPECT_TRUE(report.no_accel_work()) << "a user_id is shading data only";
    expect_user_ids({{"left", 5u}, {"/World/Ball", 77u}, {"right cube", 0xFFFFFFFEu}});
}

}  // namespace
}  // namespace strata

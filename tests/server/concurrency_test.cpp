// Eight clients editing and rendering at once for a few seconds: no crash, no error but the
// expected ones, every render at one version, and a final state equal to a sequential replay of
// the accepted batches in version order.

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <random>

#include "protocol/edit_parser.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

/// Everything observable about a scene, as JSON, for comparing two scenes.
Json fingerprint(const Scene& s) {
    Json j;
    j["version"] = s.version();
    s.meshes().for_each([&](MeshHandle, const MeshRecord& m) {
        Json p = Json::array();
        for (const Vec3& v : m.positions) p.push_back({v.x, v.y, v.z});
        Json t = Json::array();
        for (const Triangle& tri : m.triangles) t.push_back({tri.x, tri.y, tri.z});
        j["meshes"][m.id] = {{"positions", p}, {"triangles", t}};
    });
    s.instances().for_each([&](InstanceHandle, const InstanceRecord& i) {
        j["instances"][i.id] = {{"mesh", s.mesh(i.mesh).value()->id},
                                {"transform", i.transform.m},
                                {"visible", i.visible},
                                {"mask", i.mask}};
    });
    s.materials().for_each([&](MaterialHandle, const MaterialRecord& m) {
        j["materials"][m.id] = {m.material.roughness, m.material.metallic};
    });
    j["camera"] = {s.camera().eye.x, s.camera().eye.y, s.camera().eye.z, s.camera().fov_y_deg};
    return j;
}

/// A random batch for client `c`: mostly its own objects, sometimes a shared one, sometimes
/// invalid.
Json random_batch(std::mt19937& rng, int c, int step) {
    const std::string me = "c" + std::to_string(c);
    auto pick = [&](int n) { return int(rng() % uint32_t(n)); };
    Json edits = Json::array();
    const int kind = pick(8);
    const std::string inst = me + "-i" + std::to_string(pick(3));
    if (kind == 0) {
        edits.push_back({{"op", "add_instance"},
                         {"id", me + "-x" + std::to_string(step)},
                         {"mesh", "shared"},
                         {"transform", {{"translate", {pick(10), pick(5), pick(10)}}}}});
    } else if (kind == 1) {
        edits.push_back({{"op", "update_mesh"},
                         {"mesh", "shared"},
                         {"positions", {0, pick(3) * 0.1, 0}},
                         {"offset", pick(8)}});
    } else if (kind == 2) {
        edits.push_back(
            {{"op", "update_material"}, {"material", "m"}, {"roughness", pick(10) / 10.0}});
    } else if (kind == 3) {
        // Invalid at index 1: nothing of this batch may land.
        edits.push_back({{"op", "set_transform"},
                         {"instance", inst},
                         {"transform", {{"translate", {1, 1, 1}}}}});
        edits.push_back({{"op", "remove_mesh"}, {"mesh", "no-such-mesh"}});
    } else if (kind == 4) {
        edits.push_back({{"op", "set_camera"}, {"eye", {pick(5), 3, 10}}});
    } else {
        edits.push_back({{"op", "set_transform"},
                         {"instance", inst},
                         {"transform",
                          {{"translate", {pick(20) - 10, 0, pick(20) - 10}},
                           {"rotate_deg", {0, pick(360), 0}}}}});
        edits.push_back({{"op", "update_instance"}, {"instance", inst}, {"visible", pick(4) != 0}});
    }
    return {{"edits", edits}};
}

TEST(Concurrency, EightClientsEditingAndRenderingMatchASequentialReplay) {
    TestServer srv;
    Json setup = {{{"op", "add_material"}, {"id", "m"}},
                  {{"op", "add_mesh"}, {"id", "shared"}, {"shape", {{"type", "box"}}}}};
    for (int c = 0; c < 8; ++c) {
        for (int i = 0; i < 3; ++i)
            setup.push_back({{"op", "add_instance"},
                             {"id", "c" + std::to_string(c) + "-i" + std::to_string(i)},
                             {"mesh", "shared"}});
    }
    const Json setup_batch = {{"edits", setup}};
    ASSERT_EQ(srv.post("/v1/edits", setup_batch).status, 200);

    std::mutex mutex;
    std::map<uint64_t, std::string> accepted;  // version -> batch text
    accepted[1] = setup_batch.dump();
    std::atomic<int> unexpected{0}, renders{0}, rejected{0};
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);

    std::vector<std::thread> clients;
    for (int c = 0; c < 8; ++c) {
        clients.emplace_back([&, c] {
            std::mt19937 rng(1234u + unsigned(c));
            auto client = srv.client();
            for (int step = 0; std::chrono::steady_clock::now() < deadline; ++step) {
                if (rng() % 4 == 0) {
                    auto r = client.Post("/v1/render", Json{{"width", 32}, {"height", 24}}.dump(),
                                         "application/json");
                    if (!r || r->status != 200 || r->get_header_value("ETag").empty()) ++unexpected;
                    ++renders;
                    continue;
                }
                const std::string text = random_batch(rng, c, step).dump();
                auto r = client.Post("/v1/edits", text, "application/json");
                if (!r) {
                    ++unexpected;
                } else if (r->status == 200) {
                    std::lock_guard lock(mutex);
                    accepted[Json::parse(r->body)["version"].get<uint64_t>()] = text;
                } else if (r->status == 422) {
                    ++rejected;
                } else {
                    ++unexpected;
                }
            }
        });
    }
    for (auto& t : clients) t.join();
    EXPECT_EQ(unexpected.load(), 0);
    EXPECT_GT(renders.load(), 0);
    EXPECT_GT(rejected.load(), 0);

    // Versions are dense: every accepted batch got its own, none was lost.
    ASSERT_EQ(accepted.rbegin()->first, accepted.size());

    auto replay = std::move(Engine::create().value());
    for (const auto& [version, text] : accepted) {
        auto parsed = protocol::parse_edit_batch(text, {});
        ASSERT_TRUE(parsed.has_value());
        auto applied = replay->apply(std::move(parsed.value().batch));
        ASSERT_TRUE(applied.has_value())
            << "version " << version << ": " << applied.error().describe();
        ASSERT_EQ(applied.value().version, version);
    }
    const Json live = srv.engine().read(fingerprint);
    const Json replayed = replay->read(fingerprint);
    EXPECT_EQ(live, replayed);
    // And the live scene still renders after all of it.
    EXPECT_EQ(srv.post("/v1/render", Json{{"width", 16}, {"height", 16}}).status, 200);
}

}  // namespace
}  // namespace strata::server::test

// GET and POST /v1/pick: parsing, client ids in the answer, and problems for bad requests.

#include <gtest/gtest.h>

#include "engine/scene/shapes.h"
#include "protocol/api.h"

namespace strata::protocol {
namespace {

using Query = std::multimap<std::string, std::string>;

class PickApi : public ::testing::Test {
protected:
    void SetUp() override {
        engine = std::move(Engine::create().value());
        EditBatch batch;
        batch.edits.push_back(add_mesh_edit("ball", make_sphere(1.0f, 32), {}));
        AddInstance a;
        a.id = "/World/Ball";
        a.mesh = "ball";
        a.user_id = 42;
        a.name = "The ball";
        batch.edits.push_back(a);
        SetCamera c;
        c.eye = Vec3(0.0f, 0.0f, 5.0f);
        c.target = Vec3(0.0f);
        batch.edits.push_back(c);
        ASSERT_TRUE(engine->apply(std::move(batch)).has_value());
    }

    std::unique_ptr<Engine> engine;
    const ApiLimits limits;
};

TEST_F(PickApi, GetAnswersTheHitUnderOnePixelWithClientIds) {
    const ApiResponse r =
        get_pick(*engine, {{"x", "50"}, {"y", "50"}, {"width", "100"}, {"height", "100"}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    const Json doc = Json::parse(r.body);
    EXPECT_EQ(doc["version"], 1);
    const Json& hit = doc["hit"];
    EXPECT_EQ(hit["instance"], "/World/Ball");
    EXPECT_EQ(hit["mesh"], "ball");
    EXPECT_EQ(hit["user_id"], 42);
    EXPECT_EQ(hit["name"], "The ball") << "the table's label fields come with a hit";
    EXPECT_FALSE(hit.contains("transform")) << "and only those";
    EXPECT_NEAR(hit["distance"].get<double>(), 4.0, 0.01);
    EXPECT_NEAR(hit["normal"][2].get<double>(), 1.0, 0.01);
    EXPECT_NEAR(hit["position"][2].get<double>(), 1.0, 0.01);
    EXPECT_TRUE(hit["primitive"].is_number_unsigned());

    const Json miss = Json::parse(
        get_pick(*engine, {{"x", "0"}, {"y", "0"}, {"width", "100"}, {"height", "100"}}).body);
    EXPECT_TRUE(miss["hit"].is_null());
    // The render's camera override: looking away, nothing is hit.
    const Json away = Json::parse(
        get_pick(
            *engine,
            {{"x", "50"}, {"y", "50"}, {"width", "100"}, {"height", "100"}, {"target", "0,0,10"}})
            .body);
    EXPECT_TRUE(away["hit"].is_null());
}

TEST_F(PickApi, PostAnswersOneEntryPerPixelInOrder) {
    const ApiResponse r = post_pick(
        *engine, R"({"width": 100, "height": 100, "pixels": [[0, 0], [50, 50], [99, 99]]})",
        limits);
    ASSERT_EQ(r.status, 200) << r.body;
    const Json hits = Json::parse(r.body)["hits"];
    ASSERT_EQ(hits.size(), 3u);
    EXPECT_TRUE(hits[0].is_null());
    EXPECT_EQ(hits[1]["instance"], "/World/Ball");
    EXPECT_TRUE(hits[2].is_null());
}

TEST_F(PickApi, BadRequestsAreProblemsNamingWhatWasWrong) {
    const struct {
        const char* body;
        int status;
        const char* pointer;
    } cases[] = {
        {R"({"width": 10, "height": 10})", 400, "/pixels"},
        {R"({"width": 10, "height": 10, "pixels": [[1]]})", 400, "/pixels/0"},
        {R"({"width": 10, "height": 10, "pixels": [[1, -1]]})", 400, "/pixels/0/1"},
        {R"({"width": 10, "height": 10, "pixels": [[1, 1], [10, 1]]})", 422, "/pixels/1"},
        {R"({"width": 0, "height": 10, "pixels": [[0, 0]]})", 400, "/width"},
        {R"({"width": 10, "height": 10, "pixels": [], "extra": 1})", 400, "/extra"},
        {R"({"width": 10, "height": 10, "pixels": []})", 422, "/pixels"},
        {R"({"width": 10, "height": 10, "pixels": [[0, 0]], "camera": {"fov_y_deg": 1e39}})", 422,
         "/camera/fov_y_deg"},
        {R"({"width": 10, "height": 10, "pixels": [[0, 0]], "camera": {"eye": [3e38, 3e38, 3e38],
            "target": [-3e38, -3e38, -3e38]}})",
         422, "/camera/eye"},
    };
    for (const auto& c : cases) {
        const ApiResponse r = post_pick(*engine, c.body, limits);
        EXPECT_EQ(r.status, c.status) << c.body << "\n" << r.body;
        EXPECT_EQ(Json::parse(r.body).value("pointer", ""), c.pointer) << c.body;
    }
    EXPECT_EQ(post_pick(*engine, "{", limits).status, 400);
    const ApiResponse missing = get_pick(*engine, {{"x", "1"}, {"width", "10"}, {"height", "10"}});
    EXPECT_EQ(missing.status, 400);
    EXPECT_EQ(Json::parse(missing.body)["pointer"], "/y");
    const ApiResponse twice =
        get_pick(*engine, {{"x", "1"}, {"x", "2"}, {"y", "1"}, {"width", "10"}, {"height", "10"}});
    EXPECT_EQ(twice.status, 400);
    EXPECT_EQ(engine->counters().picks, 0u);
}

}  // namespace
}  // namespace strata::protocol

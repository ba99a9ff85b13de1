// GET /v1/scene/{meshes,instances,materials}: pages in slot order, cursors, filters, and the
// version every page was read at.

#include <set>

#include <gtest/gtest.h>

#include "engine/scene/shapes.h"
#include "protocol/api.h"

namespace strata::protocol {
namespace {

using Query = std::multimap<std::string, std::string>;

class SceneList : public ::testing::Test {
protected:
    void SetUp() override {
        engine = std::move(Engine::create().value());
        EditBatch batch;
        batch.edits.push_back(add_mesh_edit("ball", make_sphere(1.0f, 8), {}));
        batch.edits.push_back(add_mesh_edit("box", make_box(Vec3(1.0f)), {}));
        for (int i = 0; i < 30; ++i) {
            AddInstance a;
            a.id = "/World/i" + std::to_string(i);
            a.mesh = i % 2 ? "box" : "ball";
            a.visible = i % 5 != 0;
            a.transform = Affine::translation(Vec3(float(i), 0.0f, 0.0f));
            batch.edits.push_back(a);
        }
        ASSERT_TRUE(engine->apply(std::move(batch)).has_value());
    }

    Json page(SceneObject kind, const Query& q, int status = 200) {
        const ApiResponse r = get_scene_list(*engine, kind, q);
        EXPECT_EQ(r.status, status) << r.body;
        return Json::parse(r.body);
    }

    /// Every id of a listing walked `limit` at a time, checking each page's version.
    std::vector<std::string> walk(SceneObject kind, Query q, std::size_t limit) {
        q.emplace("limit", std::to_string(limit));
        std::vector<std::string> ids;
        for (int pages = 0; pages < 100; ++pages) {
            const Json p = page(kind, q);
            EXPECT_LE(p["items"].size(), limit);
            for (const Json& item : p["items"]) ids.push_back(item["id"]);
            if (p["next_cursor"].is_null()) return ids;
            q.erase("cursor");
            q.emplace("cursor", p["next_cursor"].get<std::string>());
        }
        ADD_FAILURE() << "the walk does not end";
        return ids;
    }

    std::unique_ptr<Engine> engine;
};

TEST_F(SceneList, PagesWalkEveryObjectOnceInAStableOrder) {
    const auto all = walk(SceneObject::Instance, {}, 1000);
    ASSERT_EQ(all.size(), 30u);
    EXPECT_EQ(all.front(), "/World/i0");
    EXPECT_EQ(walk(SceneObject::Instance, {}, 7), all);
    EXPECT_EQ(walk(SceneObject::Instance, {}, 1), all);
    EXPECT_EQ(walk(SceneObject::Mesh, {}, 1), (std::vector<std::string>{"ball", "box"}));
    EXPECT_TRUE(walk(SceneObject::Material, {}, 5).empty());
    // A full last page has no cursor: no empty page follows it.
    EXPECT_TRUE(page(SceneObject::Instance, {{"limit", "30"}})["next_cursor"].is_null());
    EXPECT_EQ(page(SceneObject::Instance, {})["items"].size(), 30u);  // default limit 100
}

TEST_F(SceneList, ItemsAreTheSingleObjectDocumentsAndThePageCarriesItsVersion) {
    const ApiResponse r = get_scene_list(*engine, SceneObject::Instance, {{"limit", "3"}});
    const Json p = Json::parse(r.body);
    EXPECT_EQ(p["version"], 1);
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    for (const Json& item : p["items"]) {
        const ApiResponse one =
            get_scene_object(*engine, SceneObject::Instance, item["id"].get<std::string>());
        EXPECT_EQ(Json::parse(one.body), item);
    }
    const Json meshes = page(SceneObject::Mesh, {});
    EXPECT_EQ(meshes["items"][1],
              Json::parse(get_scene_object(*engine, SceneObject::Mesh, "box").body));
}

TEST_F(SceneList, FiltersKeepOnlyMatchingInstancesAcrossPages) {
    const auto boxes = walk(SceneObject::Instance, {{"mesh", "box"}}, 4);
    EXPECT_EQ(boxes.size(), 15u);
    for (const auto& id : boxes) EXPECT_EQ(std::stoi(id.substr(8)) % 2, 1) << id;
    const auto hidden = walk(SceneObject::Instance, {{"visible", "false"}}, 2);
    EXPECT_EQ(hidden, (std::vector<std::string>{"/World/i0", "/World/i5", "/World/i10",
                                                "/World/i15", "/World/i20", "/World/i25"}));
    const auto visible_balls =
        walk(SceneObject::Instance, {{"visible", "true"}, {"mesh", "ball"}}, 100);
    EXPECT_EQ(visible_balls.size(), 12u);
}

TEST_F(SceneList, ObjectsThatExistThroughoutAppearOnceWhileOthersComeAndGo) {
    Query q{{"limit", "4"}};
    std::vector<std::string> seen;
    int round = 0;
    while (true) {
        const Json p = page(SceneObject::Instance, q);
        for (const Json& item : p["items"]) seen.push_back(item["id"]);
        // Between pages: remove an early and a late instance, add two new ones (which reuse the
        // freed slots).
        EditBatch churn;
        churn.edits.push_back(RemoveInstance{"/World/i" + std::to_string(round * 2)});
        churn.edits.push_back(RemoveInstance{"/World/i" + std::to_string(29 - round)});
        for (int k = 0; k < 2; ++k) {
            AddInstance a;
            a.id = "new" + std::to_string(round) + "_" + std::to_string(k);
            a.mesh = "ball";
            churn.edits.push_back(a);
        }
        if (round < 5) {
            ASSERT_TRUE(engine->apply(std::move(churn)).has_value());
        }
        ++round;
        if (p["next_cursor"].is_null()) break;
        q.erase("cursor");
        q.emplace("cursor", p["next_cursor"].get<std::string>());
    }
    const std::set<std::string> unique(seen.begin(), seen.end());
    EXPECT_EQ(unique.size(), seen.size()) << "an object appeared twice";
    // Never removed during the walk: i10 ... i23, odd i1 ... i9, and i24.
    for (int i = 0; i < 30; ++i) {
        const bool removed = (i % 2 == 0 && i < 10) || i >= 25;
        if (!removed) {
            EXPECT_TRUE(unique.count("/World/i" + std::to_string(i))) << i;
        }
    }
}

TEST_F(SceneList, BadQueriesAreRefusedNamingTheParameter) {
    const struct {
        SceneObject kind;
        Query query;
        int status;
        const char* pointer;
    } cases[] = {
        {SceneObject::Instance, {{"limit", "0"}}, 400, "/limit"},
        {SceneObject::Instance, {{"limit", "10001"}}, 400, "/limit"},
        {SceneObject::Instance, {{"limit", "ten"}}, 400, "/limit"},
        {SceneObject::Instance, {{"limit", "5"}, {"limit", "6"}}, 400, "/limit"},
        {SceneObject::Instance, {{"cursor", "meshes-1"}}, 400, "/cursor"},
        {SceneObject::Instance, {{"cursor", "instances-zz"}}, 400, "/cursor"},
        {SceneObject::Instance, {{"cursor", "instances-"}}, 400, "/cursor"},
        {SceneObject::Instance, {{"cursor", "instances-1ffffffff"}}, 400, "/cursor"},
        {SceneObject::Instance, {{"visible", "yes"}}, 400, "/visible"},
        {SceneObject::Instance, {{"mesh", "nope"}}, 404, "/mesh"},
        {SceneObject::Instance, {{"parent", "g"}}, 404, "/parent"},
        {SceneObject::Group, {{"parent", "g"}}, 404, "/parent"},
        {SceneObject::Group, {{"mesh", "ball"}}, 400, "/mesh"},
        {SceneObject::Material, {{"parent", ""}}, 400, "/parent"},
        {SceneObject::Mesh, {{"mesh", "ball"}}, 400, "/mesh"},
        {SceneObject::Material, {{"visible", "true"}}, 400, "/visible"},
    };
    for (const auto& c : cases) {
        const Json problem = page(c.kind, c.query, c.status);
        EXPECT_EQ(problem["pointer"], c.pointer) << problem.dump();
    }
    // A cursor past the end is an empty last page, not an error.
    const Json end = page(SceneObject::Instance, {{"cursor", "instances-ffff"}});
    EXPECT_TRUE(end["items"].empty());
    EXPECT_TRUE(end["next_cursor"].is_null());
}

// Groups: car > wheels > i0, i2; car > i4; i1 under wheels2 (a second child group of car).
class SceneListGroups : public SceneList {
protected:
    void SetUp() override {
        SceneList::SetUp();
        EditBatch b;
        b.edits.emplace_back(AddGroup{"car", std::nullopt, Affine::translation({0, 0, 5}), true});
        b.edits.emplace_back(AddGroup{"wheels", std::string("car"), Affine::identity(), false});
        b.edits.emplace_back(AddGroup{"wheels2", std::string("car"), Affine::identity(), true});
        for (const auto& [id, parent] : {std::pair("/World/i4", "car"),
                                         {"/World/i2", "wheels"},
                                         {"/World/i0", "wheels"},
                                         {"/World/i1", "wheels2"}}) {
            UpdateInstance u;
            u.instance = id;
            u.parent = std::optional<std::string>(parent);
            b.edits.emplace_back(u);
        }
        ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    }

    Json children(const std::string& group, const Query& q, int status = 200) {
        const ApiResponse r = get_group_children(*engine, group, q);
        EXPECT_EQ(r.status, status) << r.body;
        return Json::parse(r.body);
    }
};

TEST_F(SceneListGroups, GroupsListAndFilterByParent) {
    EXPECT_EQ(walk(SceneObject::Group, {}, 1),
              (std::vector<std::string>{"car", "wheels", "wheels2"}));
    EXPECT_EQ(walk(SceneObject::Group, {{"parent", ""}}, 1), (std::vector<std::string>{"car"}));
    EXPECT_EQ(walk(SceneObject::Group, {{"parent", "car"}}, 1),
              (std::vector<std::string>{"wheels", "wheels2"}));
    // Children of a group come in slot order, whatever order they joined in.
    EXPECT_EQ(walk(SceneObject::Instance, {{"parent", "wheels"}}, 1),
              (std::vector<std::string>{"/World/i0", "/World/i2"}));
    EXPECT_EQ(walk(SceneObject::Instance, {{"parent", ""}}, 1000).size(), 26u);
    EXPECT_EQ(walk(SceneObject::Instance, {{"parent", "wheels"}, {"mesh", "ball"}}, 5),
              (std::vector<std::string>{"/World/i0", "/World/i2"}));
    const Json doc = page(SceneObject::Instance, {{"parent", "wheels"}})["items"][0];
    EXPECT_EQ(doc["parent"], "wheels");
    EXPECT_EQ(doc["visible"], false);  // i0 is hidden on its own (i % 5 == 0)
    EXPECT_EQ(doc["world_visible"], false);
    EXPECT_EQ(doc["world_transform"][11], 5);
    const Json car = Json::parse(get_scene_object(*engine, SceneObject::Group, "car").body);
    EXPECT_EQ(car["children"]["groups"], 2);
    EXPECT_EQ(car["children"]["instances"], 1);
    EXPECT_TRUE(car["parent"].is_null());
    EXPECT_EQ(get_scene_object(*engine, SceneObject::Group, "nope").status, 404);
}

TEST_F(SceneListGroups, ChildrenPageThroughGroupsThenInstances) {
    std::vector<std::string> seen;
    Query q{{"limit", "1"}};
    for (int pages = 0; pages < 10; ++pages) {
        const Json p = children("car", q);
        for (const Json& item : p["items"])
            seen.push_back(item["kind"].get<std::string>() + ":" + item["id"].get<std::string>());
        if (p["next_cursor"].is_null()) break;
        q.erase("cursor");
        q.emplace("cursor", p["next_cursor"].get<std::string>());
    }
    EXPECT_EQ(seen,
              (std::vector<std::string>{"group:wheels", "group:wheels2", "instance:/World/i4"}));
    EXPECT_EQ(children("nope", {}, 404)["status"], 404);
    EXPECT_EQ(children("car", {{"cursor", "instances-1"}}, 400)["pointer"], "/cursor");
    EXPECT_EQ(children("car", {{"depth", "1"}}, 400)["pointer"], "/depth");
}

TEST_F(SceneListGroups, TheTreeNestsToTheAskedDepthWithinItsNodeBudget) {
    auto tree = [&](const Query& q, int status = 200) {
        const ApiResponse r = get_scene_tree(*engine, q);
        EXPECT_EQ(r.status, status) << r.body;
        return Json::parse(r.body);
    };
    const Json shallow = tree({{"depth", "0"}});
    ASSERT_EQ(shallow["groups"].size(), 1u);
    EXPECT_EQ(shallow["groups"][0]["group_count"], 2);
    EXPECT_FALSE(shallow["groups"][0].contains("groups"));
    EXPECT_EQ(shallow["instances"].size(), 26u);
    const Json deep = tree({{"depth", "2"}});
    const Json& wheels = deep["groups"][0]["groups"][0];
    EXPECT_EQ(wheels["id"], "wheels");
    EXPECT_EQ(wheels["world_visible"], false);
    EXPECT_EQ(wheels["instances"].size(), 2u);
    EXPECT_FALSE(deep["truncated"]);
    const Json cut = tree({{"depth", "2"}, {"max_nodes", "3"}});
    EXPECT_TRUE(cut["truncated"]);
    const Json sub = tree({{"group", "car"}, {"depth", "0"}});
    EXPECT_EQ(sub["group"], "car");
    EXPECT_EQ(sub["groups"].size(), 2u);
    EXPECT_EQ(tree({{"group", "nope"}}, 404)["pointer"], "/group");
    EXPECT_EQ(tree({{"depth", "65"}}, 400)["pointer"], "/depth");
    EXPECT_EQ(tree({{"limit", "5"}}, 400)["pointer"], "/limit");
}

}  // namespace
}  // namespace strata::protocol

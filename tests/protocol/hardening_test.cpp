// Protocol defences against hostile input: text that is not UTF-8 or holds control characters,
// and small requests that would generate huge data.

#include <chrono>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/durable/journal_format.h"
#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "protocol/api.h"
#include "protocol/edit_parser.h"
#include "protocol/safe_text.h"

namespace strata::protocol {
namespace {

TEST(Utf8, WellFormedTextIsValidAndEveryMalformedClassIsNot) {
    EXPECT_TRUE(is_valid_utf8(""));
    EXPECT_TRUE(is_valid_utf8("plain /World/Looks"));
    EXPECT_TRUE(is_valid_utf8("\xC3\xA9t\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x8C\x8D"));
    for (const char* bad : {"\xFF", "\xC3", "\xC3\x28", "\xC0\xAF", "\xE0\x80\xAF", "\xED\xA0\x80",
                            "\xF4\x90\x80\x80", "\xF0\x9F\x8C", "\x80", "ok\xFE"}) {
        EXPECT_FALSE(is_valid_utf8(bad)) << bad;
    }
    EXPECT_EQ(to_valid_utf8("a\xFF"
                            "b\xC3"),
              "a\xEF\xBF\xBD"
              "b\xEF\xBF\xBD");
    EXPECT_EQ(to_valid_utf8("\xC3\xA9"), "\xC3\xA9");
}

TEST(LogText, ControlCharactersAndBadBytesAreEscapedSoNoRecordCanBeForged) {
    EXPECT_EQ(escape_for_log("GET /a\r\n2026-01-01 info forged"),
              "GET /a\\x0d\\x0a2026-01-01 info forged");
    EXPECT_EQ(escape_for_log("tab\there\x7F"), "tab\\x09here\\x7f");
    EXPECT_EQ(escape_for_log("bad \xFF byte"), "bad \\xff byte");
    EXPECT_EQ(escape_for_log("C1 \xC2\x85 and LS \xE2\x80\xA8"),
              "C1 \\xc2\\x85 and LS \\xe2\\x80\\xa8");
    // A literal backslash is doubled, so "\x0a" in the input cannot pass for an escaped LF.
    EXPECT_EQ(escape_for_log("a\\x0ab"), "a\\\\x0ab");
    EXPECT_EQ(escape_for_log("caf\xC3\xA9"), "caf\xC3\xA9");
}

TEST(JsonAnswers, InvalidUtf8InAProblemIsReplacedNotThrown) {
    // nlohmann's dump() throws type_error 316 on invalid UTF-8: every answer goes through
    // dump_json, which replaces the bad bytes instead.
    const Problem p = make_problem(ProblemType::NotFound, "no mesh with id '\xFF\xFE'");
    ApiResponse r;
    ASSERT_NO_THROW(r = problem_response(p));
    EXPECT_EQ(r.status, 404);
    EXPECT_TRUE(is_valid_utf8(r.body));
    EXPECT_THAT(r.body, ::testing::HasSubstr("\xEF\xBF\xBD"));
    EXPECT_TRUE(Json::accept(r.body));
}

TEST(Ids, ControlCharactersAreRefusedAtTheirPointer) {
    for (const char* id :
         {R"("a\nb")", R"("\u0000")", R"("tab\there")", R"("del\u007f")", R"("c1\u0085")"}) {
        auto r = parse_edit_batch(
            std::string(R"({"edits": [{"op": "add_material", "id": )") + id + "}]}", {});
        ASSERT_FALSE(r.has_value()) << id;
        EXPECT_EQ(r.error().pointer, "/edits/0/id") << id;
        EXPECT_THAT(r.error().detail, ::testing::HasSubstr("control character")) << id;
    }
    EXPECT_TRUE(parse_edit_batch(
                    R"({"edits": [{"op": "add_material", "id": "/World/Looks/caf\u00e9"}]})", {})
                    .has_value());
}

TEST(Shapes, TheShapesOfOneBatchGenerateABoundedNumberOfTriangles) {
    // Each sphere is 4M triangles from ~60 bytes; eight of them used to be generated (~800 MB)
    // before anything could refuse the batch.
    std::string edits;
    for (int i = 0; i < 8; ++i) {
        edits += std::string(i ? "," : "") + R"({"op": "add_mesh", "id": "s)" + std::to_string(i) +
                 R"(", "shape": {"type": "sphere", "segments": 2048}})";
    }
    const auto start = std::chrono::steady_clock::now();
    auto r = parse_edit_batch(R"({"edits": [)" + edits + "]}", {});
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().type, ProblemType::TooLarge);
    EXPECT_EQ(r.error().pointer, "/edits/4/shape");
    EXPECT_EQ(r.error().status, 413);
    // Four spheres were generated, not eight (a correctness bound, not a benchmark).
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(30));
}

}  // namespace
}  // namespace strata::protocol

namespace strata::protocol {
namespace {

/// A snapshot file with a valid checksum around `scene`: only the rules can refuse it.
std::string snapshot_of(EditBatch scene) {
    return durable::encode_snapshot(scene, 7);
}

TEST(Ids, ASnapshotWhoseIdsBreakTheIdRuleIsRefusedAndChangesNothing) {
    auto engine = std::move(Engine::create().value());
    ASSERT_TRUE(
        engine->apply(EditBatch{{add_mesh_edit("ball", make_sphere(1.0f, 8), {})}}).has_value());
    for (const std::string& bad :
         {std::string("m\xff"), std::string("cr\rlf\n"), std::string("esc\x1b[2J"),
          std::string("\xe2\x80\xa8"), std::string(1 << 20, 'x'), std::string()}) {
        SCOPED_TRACE(bad.size() > 20 ? "a 1 MB id" : bad);
        EditBatch scene;
        scene.edits.push_back(add_mesh_edit(bad, make_sphere(1.0f, 8), {}));
        const ApiResponse r = post_snapshot(*engine, snapshot_of(std::move(scene)), std::nullopt);
        EXPECT_EQ(r.status, 422) << r.body;
        const Json problem = Json::parse(r.body);  // the problem itself is valid JSON
        EXPECT_THAT(problem["detail"].get<std::string>(), ::testing::HasSubstr("mesh id"));
        EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 1u);
        EXPECT_FALSE(engine->read([](const Scene& s) { return s.find_mesh("ball").is_null(); }));
    }
    // An instance named by a stored id that breaks the rule cannot exist either: the lookup of
    // a reference never finds one, and the answer stays valid JSON.
    EditBatch scene;
    scene.edits.push_back(add_mesh_edit("ball", make_sphere(1.0f, 8), {}));
    AddInstance i;
    i.id = "ok";
    i.mesh = "m\xff";
    scene.edits.push_back(i);
    const ApiResponse r = post_snapshot(*engine, snapshot_of(std::move(scene)), std::nullopt);
    EXPECT_EQ(r.status, 422) << r.body;
    EXPECT_TRUE(Json::accept(r.body)) << "the problem is valid JSON";
}

TEST(Budgets, AJsonDocumentOverItsValueBudgetIsRefusedWhileParsing) {
    JsonLimits limits;
    limits.max_values = 100;
    // Long number arrays are packed, not counted: a mesh's 3000 coordinates fit.
    std::string numbers = "[0";
    for (int i = 1; i < 3000; ++i) numbers += ",1";
    EXPECT_TRUE(parse_json(R"({"positions": )" + numbers + "]}", limits).has_value());
    // Objects, strings and short arrays are: 60 clears are 120 values.
    std::string clears = R"({"edits": [{"op": "clear"})";
    for (int i = 1; i < 60; ++i) clears += R"(, {"op": "clear"})";
    auto r = parse_json(clears + "]}", limits);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().type, ProblemType::TooLarge);
    EXPECT_EQ(r.error().status, 413);
    EXPECT_THAT(r.error().detail, ::testing::HasSubstr("--max-json-values"));
}

TEST(Budgets, ABatchOverTheEditCountIsRefusedBeforeItsEditsAreBuilt) {
    std::string clears = R"({"edits": [{"op": "clear"})";
    for (int i = 1; i < 5; ++i) clears += R"(, {"op": "clear"})";
    clears += "]}";
    EXPECT_TRUE(parse_edit_batch(clears, {}, 5).has_value());
    auto r = parse_edit_batch(clears, {}, 4);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().pointer, "/edits");
    EXPECT_EQ(r.error().status, 413);
    EXPECT_THAT(r.error().detail, ::testing::HasSubstr("5 edits, more than 4 (--max-batch-edits)"));
    // Through the endpoint, with the limit from ApiLimits.
    auto engine = std::move(Engine::create().value());
    ApiLimits limits;
    limits.max_batch_edits = 4;
    EXPECT_EQ(post_edits(*engine, clears, std::nullopt, limits).status, 413);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 0u);
}

TEST(Budgets, ASnapshotOfManyEditsIsRefusedFromItsCount) {
    // 100,000 one-byte clears: a small file that would decode into 25 MB of edits.
    EditBatch clears;
    clears.edits.assign(100000, Clear{});
    const std::string file = snapshot_of(std::move(clears));
    auto engine = std::move(Engine::create().value());
    const ApiResponse r = post_snapshot(*engine, file, std::nullopt, nullptr, 1000);
    EXPECT_EQ(r.status, 413) << r.body;
    EXPECT_THAT(r.body, ::testing::HasSubstr("100000 edits, more than 1000"));
    EXPECT_EQ(post_snapshot(*engine, file, std::nullopt, nullptr, 100000).status, 200);
}

TEST(Groups, NestedScalesThatOverflowAWorldTransformAre422NamingTheChain) {
    // 64 nested groups scaled 1e6 each: every local transform is valid, their product is not.
    auto engine = std::move(Engine::create().value());
    std::string edits = R"({"op": "add_mesh", "id": "ball", "shape": {"type": "sphere"}})";
    for (int d = 0; d < 64; ++d) {
        edits += R"(, {"op": "add_group", "id": "g)" + std::to_string(d) + "\"" +
                 (d ? R"(, "parent": "g)" + std::to_string(d - 1) + "\"" : std::string()) +
                 R"(, "transform": {"scale": [1e6, 1e6, 1e6]}})";
    }
    edits += R"(, {"op": "add_instance", "id": "i", "mesh": "ball", "parent": "g63"})";
    const ApiResponse r = post_edits(*engine, R"({"edits": [)" + edits + "]}", std::nullopt, {});
    EXPECT_EQ(r.status, 422) << r.body;
    const Json problem = Json::parse(r.body);
    EXPECT_THAT(problem["detail"].get<std::string>(),
                ::testing::HasSubstr("through the group chain 'g0' > 'g1' > 'g2'"));
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 0u);
    // The scene answers valid JSON with no null transforms (nothing was applied).
    EXPECT_EQ(get_scene(*engine).status, 200);
}

}  // namespace
}  // namespace strata::protocol

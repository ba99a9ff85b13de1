// Loading scripts: step kinds, comments, and an error naming the line for every kind of mistake.

#include <sstream>

#include <gtest/gtest.h>

#include "clients/cli/script.h"

namespace strata::cli {
namespace {

Outcome<Script> load(const std::string& text) {
    std::istringstream in(text);
    return load_script(in, "test.jsonl");
}

/// The failure of loading `text`: "line N: message".
std::string error_of(const std::string& text) {
    auto s = load(text);
    return s.has_value() ? "(loaded)" : s.error().describe();
}

TEST(ScriptLoader, ReadsEveryStepKindAndSkipsComments) {
    auto s = load(
        "# a comment\n"
        "\n"
        "   # an indented comment\n"
        R"({"edits": [{"op": "clear"}], "label": "start"})"
        "\n"
        R"({"commit": {}, "expect": {"tlas": "none"}})"
        "\r\n"
        R"({"plan": {}})"
        "\n"
        R"({"repeat": 2, "var": "f", "steps": [{"render": {}, "out": "f{f}.png"}, {"commit": {}}]})"
        "\n");
    ASSERT_TRUE(s.has_value()) << s.error().describe();
    const Script& script = s.value();
    ASSERT_EQ(script.steps.size(), 4u);
    EXPECT_EQ(script.steps[0].kind, StepKind::Edits);
    EXPECT_EQ(script.steps[0].label, "start");
    EXPECT_EQ(script.steps[1].kind, StepKind::Commit);
    EXPECT_TRUE(script.steps[1].expect.has_value());
    EXPECT_EQ(script.steps[2].kind, StepKind::Plan);
    const Step& repeat = script.steps[3];
    EXPECT_EQ(repeat.kind, StepKind::Repeat);
    EXPECT_EQ(repeat.var, "f");
    EXPECT_EQ(repeat.line, 7u);
    ASSERT_EQ(repeat.steps.size(), 2u);
    EXPECT_EQ(repeat.steps[0].kind, StepKind::Render);
    EXPECT_EQ(repeat.steps[0].line, 7u);
    EXPECT_TRUE(repeat.steps[0].out.has_value());
}

TEST(ScriptLoader, AMalformedLineIsRefusedWithItsNumber) {
    EXPECT_EQ(error_of("{\"commit\": {}}\n{\"edits\": [}\n").substr(0, 16), "line 2: not JSON");
    EXPECT_EQ(error_of("{\"commit\": {}} trailing\n").substr(0, 16), "line 1: not JSON");
}

TEST(ScriptLoader, DuplicateKeysAreRefused) {
    EXPECT_EQ(error_of(R"({"commit": {}, "expect": {"tlas": "none", "tlas": "update"}})"),
              "line 1: member \"tlas\" appears twice in one object");
}

TEST(ScriptLoader, AnUnknownStepKindIsRefused) {
    EXPECT_NE(error_of(R"({"comit": {}})").find("line 1: unknown step (members: comit)"),
              std::string::npos);
    EXPECT_NE(error_of(R"([1, 2])").find("a step is a JSON object"), std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "render": {}})").find("both \"commit\" and \"render\""),
              std::string::npos);
}

TEST(ScriptLoader, UnknownMembersOfAStepAreRefused) {
    EXPECT_NE(error_of(R"({"commit": {}, "expcet": {}})").find("unknown member \"expcet\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"edits": [], "expect": {}})").find("unknown member \"expect\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {"now": true}})").find("takes no options"), std::string::npos);
    EXPECT_NE(error_of(R"({"edits": {}})").find("must be an array"), std::string::npos);
    EXPECT_NE(error_of(R"({"render": []})").find("must be a render request object"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"repeat": 2, "steps": []})").find("non-empty array"), std::string::npos);
    EXPECT_NE(error_of(R"({"repeat": 2, "var": "2x", "steps": [{"commit": {}}]})")
                  .find("\"var\" must be a name"),
              std::string::npos);
}

TEST(ScriptLoader, ABadExpectationFieldIsRefused) {
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"blas_rebuild": 0}})")
                  .find("line 1: unknown member \"blas_rebuild\" in \"expect\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"tlas": "updated"}})")
                  .find("expect.tlas: expected one of \"none\", \"update\", \"rebuild\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"blas_refits": "many"}})")
                  .find("expect.blas_refits: expected a number"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"blas_refits": {"least": 1}}})")
                  .find("unknown member \"least\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"blas_refits": {}}})")
                  .find("give \"min\", \"max\" or both"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"rebuilt": {"ball": "moved"}}})")
                  .find("expect.rebuilt.ball: expected one of \"added\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"refit": {"ball": "added"}}})")
                  .find("expected one of \"positions_changed\", \"refit_requested\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"commit": {}, "expect": {"released": {"ball": "added"}}})")
                  .find("expected an array of mesh ids"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"plan": {}, "expect": {"max_ms": 1}})").find("a plan takes no time"),
              std::string::npos);
}

TEST(ScriptLoader, PickAndListStepsAreReadWithTheirExpectations) {
    auto s = load(
        R"({"pick": {"x": 3, "y": "{1 + 1}", "width": 8, "height": 8, "camera": {"fov_y_deg": 30}}, "expect": {"hit.instance": "a"}})"
        "\n"
        R"({"list": "instances", "filter": {"mesh": "rock", "visible": true}, "expect": {"count": 3}, "label": "rocks"})"
        "\n"
        R"({"list": "meshes"})");
    ASSERT_TRUE(s.has_value()) << s.error().describe();
    ASSERT_EQ(s->steps.size(), 3u);
    EXPECT_EQ(s->steps[0].kind, StepKind::Pick);
    EXPECT_TRUE(s->steps[0].expect.has_value());
    EXPECT_EQ(s->steps[1].kind, StepKind::List);
    EXPECT_EQ(s->steps[1].collection, "instances");
    EXPECT_TRUE(s->steps[1].body.has_value());
    EXPECT_EQ(s->steps[1].label, "rocks");
    EXPECT_EQ(s->steps[2].collection, "meshes");
    EXPECT_FALSE(s->steps[2].body.has_value());
    EXPECT_STREQ(step_kind_name(StepKind::Pick), "pick");
    EXPECT_STREQ(step_kind_name(StepKind::List), "list");
}

TEST(ScriptLoader, MalformedPickAndListStepsAreRefused) {
    EXPECT_NE(
        error_of(R"({"pick": {"x": 3, "y": 4, "width": 8}})").find("\"pick\" needs \"height\""),
        std::string::npos);
    EXPECT_NE(error_of(R"({"pick": [3, 4]})").find("\"pick\" must be an object"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"pick": {"x": 3, "y": 4, "width": 8, "height": 8, "z": 1}})")
                  .find("unknown member \"z\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"pick": {"x": 3, "y": 4, "width": 8, "height": 8}, "out": "a.png"})")
                  .find("unknown member \"out\""),
              std::string::npos);
    EXPECT_NE(
        error_of(
            R"({"pick": {"x": 3, "y": 4, "width": 8, "height": 8}, "expect": {"tlas": "none"}})")
            .find("unknown member \"tlas\""),
        std::string::npos);
    EXPECT_NE(error_of(R"({"list": "rocks"})").find("one of meshes, instances, materials"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"list": "instances", "filter": {"cursor": "x"}})")
                  .find("a list step reads every page itself"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"list": "instances", "filter": {"mesh": ["a"]}})")
                  .find("filter.mesh: expected a string, number or boolean"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"list": "instances", "expect": {"hit": true}})")
                  .find("unknown member \"hit\""),
              std::string::npos);
    EXPECT_NE(error_of(R"({"pick": {"x": 1, "y": 1, "width": 2, "height": 2}, "list": "meshes"})")
                  .find("this one has both \"pick\" and \"list\""),
              std::string::npos);
}

TEST(ScriptLoader, ABadExpressionIsRefusedWithItsLine) {
    EXPECT_NE(
        error_of(
            "{\"commit\": {}}\n\n"
            R"({"repeat": 3, "steps": [{"edits": [{"op": "set_camera", "eye": ["{n *}", 0, 1]}]}]})")
            .find("line 3: bad expression 'n *'"),
        std::string::npos);
    EXPECT_NE(error_of(R"({"edits": [{"op": "remove_instance", "instance": "i{n}"}]})")
                  .find("no repeat encloses this step"),
              std::string::npos);
    EXPECT_NE(error_of(R"({"repeat": "{k}", "steps": [{"commit": {}}]})").find("unknown name 'k'"),
              std::string::npos);
}

TEST(ScriptLoader, AnEmptyScriptIsRefused) {
    EXPECT_EQ(error_of("# nothing but a comment\n\n"), "test.jsonl has no steps");
}

TEST(ScriptLoader, AMissingFileIsRefused) {
    auto s = load_script_file("/nonexistent/script.jsonl");
    ASSERT_FALSE(s.has_value());
    EXPECT_NE(s.error().message.find("cannot open script"), std::string::npos);
}

}  // namespace
}  // namespace strata::cli

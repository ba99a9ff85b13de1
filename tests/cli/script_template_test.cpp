// JSON templates: substitutions in strings, numbers from whole expressions, escapes, padding and
// inline repeats spliced into arrays.

#include <gtest/gtest.h>

#include "clients/cli/script_template.h"

namespace strata::cli {
namespace {

Json instantiate(const Json& tmpl, double n, std::vector<std::string> names = {"n"}) {
    auto t = JsonTemplate::compile(tmpl, names);
    EXPECT_TRUE(t.has_value()) << (t.has_value() ? "" : t.error().message);
    if (!t) return nullptr;
    Bindings vars;
    vars.push("n", n);
    auto j = t.value().instantiate(vars);
    EXPECT_TRUE(j.has_value()) << (j.has_value() ? "" : j.error().message);
    return j.has_value() ? j.value() : Json();
}

std::string compile_error(const Json& tmpl, std::vector<std::string> names = {"n"}) {
    auto t = JsonTemplate::compile(tmpl, names);
    return t.has_value() ? "" : t.error().message;
}

TEST(ScriptTemplate, SubstitutesInsideAnyString) {
    const Json out = instantiate({{"id", "ball-{n}"}, {"path", "f{n*2}-{n+0.5}.png"}}, 3);
    EXPECT_EQ(out, (Json{{"id", "ball-3"}, {"path", "f6-3.5.png"}}));
}

TEST(ScriptTemplate, AWholeExpressionBecomesANumber) {
    const Json out = instantiate({{"translate", {"{n}", 0, "{n * 0.5}"}}, {"k", "{-n}"}}, 3);
    EXPECT_EQ(out["translate"], (Json{3, 0, 1.5}));
    EXPECT_TRUE(out["translate"][0].is_number_integer());
    EXPECT_TRUE(out["translate"][2].is_number_float());
    EXPECT_EQ(out["k"], -3);
}

TEST(ScriptTemplate, DoubledBracesAreLiteralAndKeysAreNeverSubstituted) {
    const Json out = instantiate({{"{n}", "{{n}} = {n}"}}, 2);
    EXPECT_EQ(out, (Json{{"{n}", "{n} = 2"}}));
}

TEST(ScriptTemplate, AWidthZeroPadsTheValue) {
    EXPECT_EQ(instantiate("frame_{n:4}.png", 7), "frame_0007.png");
    EXPECT_EQ(instantiate("{n:4}", 7), "0007");  // padded text stays text
    EXPECT_EQ(instantiate("{n - 10:4}", 3), "-007");
    EXPECT_EQ(instantiate("{n:2}", 12345), "12345");
}

TEST(ScriptTemplate, InlineRepeatsSpliceIntoArrays) {
    const Json tmpl = {1,
                       {{"repeat", 3}, {"var", "i"}, {"items", {"{i}", "{i + n}"}}},
                       {{"repeat", 0}, {"items", {99}}},
                       2};
    EXPECT_EQ(instantiate(tmpl, 10), (Json{1, 0, 10, 1, 11, 2, 12, 2}));
}

TEST(ScriptTemplate, NestedRepeatsBuildAGridInOneArray) {
    const Json tmpl = Json::array(
        {{{"repeat", 2},
          {"var", "j"},
          {"items",
           Json::array({{{"repeat", 3}, {"var", "i"}, {"items", Json::array({"{j*3+i}"})}}})}}});
    EXPECT_EQ(instantiate(tmpl, 0), (Json{0, 1, 2, 3, 4, 5}));
}

TEST(ScriptTemplate, ARepeatCountMayBeAnExpression) {
    const Json tmpl = Json::array({{{"repeat", "{n + 1}"}, {"items", {"x{n}"}}}});
    EXPECT_EQ(instantiate(tmpl, 2), (Json{"x0", "x1", "x2"}));
}

TEST(ScriptTemplate, ARepeatWithoutAVarBindsNAndHidesTheOuterN) {
    const Json tmpl = Json::array({{{"repeat", 2}, {"items", {"{n}"}}}});
    EXPECT_EQ(instantiate(tmpl, 7), (Json{0, 1}));
}

TEST(ScriptTemplate, RefusesBadTemplatesWhenCompiled) {
    EXPECT_NE(compile_error("a{n").find("unclosed '{'"), std::string::npos);
    EXPECT_NE(compile_error("a}").find("unmatched '}'"), std::string::npos);
    EXPECT_NE(compile_error("{m}").find("unknown name 'm'"), std::string::npos);
    EXPECT_NE(compile_error("{n:x}").find("bad width"), std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", 2}, {"items", {1}}, {"extra", 1}}}))
                  .find("unknown member \"extra\""),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", 2}}})).find("needs \"items\""),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", -1}, {"items", {1}}}})).find("whole number"),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", 1.5}, {"items", {1}}}})).find("whole number"),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", 1e9}, {"items", {1}}}})).find("whole number"),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", "n"}, {"items", {1}}}})).find("repeat count"),
              std::string::npos);
    EXPECT_NE(compile_error(Json::array({{{"repeat", 2}, {"var", "pi"}, {"items", {1}}}}))
                  .find("not a usable name"),
              std::string::npos);
    // The variable of a repeat is in scope inside it only.
    EXPECT_NE(compile_error(Json::array({{{"repeat", 2}, {"var", "i"}, {"items", {1}}}, "{i}"}))
                  .find("unknown name 'i'"),
              std::string::npos);
}

TEST(ScriptTemplate, EvaluationErrorsAreReportedNotThrown) {
    auto t = JsonTemplate::compile({{"x", "{1 / n}"}}, {"n"});
    ASSERT_TRUE(t.has_value());
    Bindings vars;
    vars.push("n", 0);
    auto j = t.value().instantiate(vars);
    ASSERT_FALSE(j.has_value());
    EXPECT_NE(j.error().message.find("division by zero"), std::string::npos);
}

TEST(ScriptTemplate, LiteralJsonComesBackUnchanged) {
    const Json doc = Json::parse(R"({"a": [1, 2.5, "x", null, true, {"b": []}], "c": {}})");
    EXPECT_EQ(instantiate(doc, 0, {}), doc);
}

}  // namespace
}  // namespace strata::cli

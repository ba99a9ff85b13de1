// Expectations against report documents: exact counts, bounds, sets of meshes with and without
// reasons, the TLAS action, and budgets only in the budgets profile.

#include <gtest/gtest.h>

#include "clients/cli/script_expect.h"

namespace strata::cli {
namespace {

/// A commit report as the protocol writes it.
Json report() {
    return Json::parse(R"({
        "version": 7, "planned": false,
        "tlas": {"action": "update", "instances": 3, "ms": 0.1},
        "blas_rebuilds": 1, "blas_refits": 1,
        "rebuilt": [{"mesh": "ball", "reason": "topology_changed", "primitives": 100, "ms": 1}],
        "refit": [{"mesh": "flag", "reason": "positions_changed", "primitives": 50, "ms": 0.2}],
        "released": ["crate"],
        "primitives_built": 100, "primitives_refit": 50,
        "memory_bytes": {"blas": 1, "tlas": 1}, "ms": 12.5, "phases": {}})");
}

Expectation compile(const Json& expect, bool has_time = true) {
    auto e = Expectation::compile(expect, {"n"}, has_time);
    EXPECT_TRUE(e.has_value()) << (e.has_value() ? "" : e.error().message);
    return e.has_value() ? std::move(e.value())
                         : Expectation::compile(Json::object(), {}, true).value();
}

std::vector<Mismatch> check(const Json& expect, bool budgets = false, double n = 0) {
    Bindings vars;
    vars.push("n", n);
    auto m = compile(expect).check(report(), vars, budgets);
    EXPECT_TRUE(m.has_value()) << (m.has_value() ? "" : m.error().message);
    return m.has_value() ? m.value() : std::vector<Mismatch>{};
}

TEST(ScriptExpect, AMatchingReportHasNoMismatches) {
    EXPECT_TRUE(check(Json::parse(R"({
        "version": 7, "tlas": "update", "tlas_instances": 3, "blas_rebuilds": 1,
        "blas_refits": {"min": 1, "max": 1}, "primitives_built": {"max": 100},
        "primitives_refit": {"min": 50},
        "rebuilt": {"ball": "topology_changed"}, "refit": ["flag"], "released": ["crate"]})"))
                    .empty());
}

TEST(ScriptExpect, ExactCountsAndBoundsReportExpectedAndActual) {
    const auto m = check(Json::parse(
        R"({"blas_rebuilds": 0, "blas_refits": {"min": 2}, "primitives_built": {"min": 1, "max": 99},
            "tlas_instances": {"max": 2}})"));
    ASSERT_EQ(m.size(), 4u);
    EXPECT_EQ(m[0].field, "tlas_instances");
    EXPECT_EQ(m[0].expected, "<= 2");
    EXPECT_EQ(m[0].actual, "3");
    EXPECT_EQ(m[1].field, "blas_rebuilds");
    EXPECT_EQ(m[1].expected, "0");
    EXPECT_EQ(m[1].actual, "1");
    EXPECT_EQ(m[2].field, "blas_refits");
    EXPECT_EQ(m[2].expected, ">= 2");
    EXPECT_EQ(m[3].field, "primitives_built");
    EXPECT_EQ(m[3].expected, "1 to 99");
    EXPECT_EQ(m[3].actual, "100");
}

TEST(ScriptExpect, ExpressionsUseTheIterationVariables) {
    EXPECT_TRUE(check({{"version", "{n + 4}"}}, false, 3).empty());
    EXPECT_EQ(check({{"version", "{n + 4}"}}, false, 2).size(), 1u);
    EXPECT_TRUE(check({{"rebuilt", {"ba{n}"}}}, false, 0).size() == 1);
}

TEST(ScriptExpect, MeshSetsNameWhatIsMissingAndWhatIsUnexpected) {
    const auto m = check({{"rebuilt", {"crate"}}, {"refit", Json::array()}});
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].field, "rebuilt");
    EXPECT_EQ(m[0].expected, "[crate]");
    EXPECT_EQ(m[0].actual, "[ball]");
    EXPECT_EQ(m[0].note, "missing: crate; unexpected: ball");
    EXPECT_EQ(m[1].field, "refit");
    EXPECT_EQ(m[1].expected, "[]");
    EXPECT_EQ(m[1].note, "unexpected: flag");
}

TEST(ScriptExpect, MeshSetsAreSetsNotLists) {
    Json r = report();
    r["rebuilt"].push_back({{"mesh", "alpha"}, {"reason", "added"}});
    auto e = compile({{"rebuilt", {"alpha", "ball"}}});
    EXPECT_TRUE(e.check(r, Bindings{}, false).value().empty());
}

TEST(ScriptExpect, ReasonsArePinnedWhenGiven) {
    const auto m = check({{"rebuilt", {{"ball", "added"}}}});
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].expected, "{ball: added}");
    EXPECT_EQ(m[0].actual, "{ball: topology_changed}");
    EXPECT_EQ(m[0].note, "ball was topology_changed");
}

TEST(ScriptExpect, TheTlasActionMustMatch) {
    const auto m = check({{"tlas", "none"}});
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].expected, "none");
    EXPECT_EQ(m[0].actual, "update");
}

TEST(ScriptExpect, TheTimeBudgetIsCheckedOnlyInTheBudgetsProfile) {
    const Json expect = {{"max_ms", 10}, {"max_primitives_built", 50}};
    // The primitive budget is a count: checked in every profile.
    auto m = check(expect, false);
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].field, "max_primitives_built");
    EXPECT_EQ(m[0].note, "over budget");
    m = check(expect, true);
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].field, "max_ms");
    EXPECT_EQ(m[0].expected, "<= 10");
    EXPECT_EQ(m[0].actual, "12.5");
    EXPECT_EQ(m[0].note, "over budget");
    EXPECT_EQ(m[1].field, "max_primitives_built");
    EXPECT_TRUE(check({{"max_ms", 13}, {"max_primitives_built", 100}}, true).empty());
    EXPECT_TRUE(check({{"max_ms", 1}, {"max_primitives_built", 100}}, false).empty());
    const Expectation e = compile(expect);
    EXPECT_EQ(e.count_budgets(), 1u);
    EXPECT_EQ(e.count_checks(), 1u);
}

TEST(ScriptExpect, AMemberMissingFromTheReportIsAMismatch) {
    auto e = compile({{"blas_rebuilds", 0}});
    const auto m = e.check(Json::object(), Bindings{}, false).value();
    ASSERT_EQ(m.size(), 1u);
    EXPECT_EQ(m[0].actual, "(absent)");
}

TEST(ScriptExpect, AnExpressionThatCannotBeEvaluatedIsAnError) {
    auto e = compile({{"version", "{1 / n}"}});
    Bindings vars;
    vars.push("n", 0);
    auto m = e.check(report(), vars, false);
    ASSERT_FALSE(m.has_value());
    EXPECT_NE(m.error().message.find("division by zero"), std::string::npos);
}

}  // namespace
}  // namespace strata::cli

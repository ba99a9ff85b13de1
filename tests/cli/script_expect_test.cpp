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

/// A pick step's answer as the runner keeps it, and a list step's.
const Json PICKED = Json::parse(
    R"({"version": 4, "hit": {"instance": "b0", "mesh": "ball", "primitive": 97,
        "distance": 7.02, "user_id": 12, "position": [0, 0, 1], "normal": [0, 0, 1]}})");
const Json MISSED = Json::parse(R"({"version": 4, "hit": null})");
const Json LISTED = Json::parse(R"({"version": 9, "count": 3, "ids": ["a", "b", "c"]})");

std::vector<Mismatch> check_answer(const Json& expect, ExpectTarget target, const Json& answer) {
    auto e = Expectation::compile(expect, {"n"}, true, target);
    EXPECT_TRUE(e.has_value()) << (e.has_value() ? "" : e.error().message);
    if (!e) return {};
    Bindings vars;
    vars.push("n", 2);
    auto m = e.value().check(answer, vars, false);
    EXPECT_TRUE(m.has_value()) << (m.has_value() ? "" : m.error().message);
    return m.has_value() ? m.value() : std::vector<Mismatch>{};
}

TEST(ScriptExpect, APickChecksWhatWasHitWithIdsAndCounts) {
    const Json all = Json::parse(
        R"({"hit": true, "hit.instance": "b0", "hit.mesh": "ball", "hit.primitive": 97,
            "hit.user_id": "{n * 6}", "hit.distance": {"min": 7, "max": 7.1}, "version": 4})");
    EXPECT_TRUE(check_answer(all, ExpectTarget::Pick, PICKED).empty());
    EXPECT_EQ(Expectation::compile(all, {"n"}, true, ExpectTarget::Pick).value().count_checks(),
              7u);
    const auto m = check_answer(Json::parse(R"({"hit.instance": "b{n}", "hit.user_id": 13})"),
                                ExpectTarget::Pick, PICKED);
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].field, "hit.user_id");
    EXPECT_EQ(m[0].actual, "12");
    EXPECT_EQ(m[1].field, "hit.instance");
    EXPECT_EQ(m[1].expected, "b2");
    EXPECT_EQ(m[1].actual, "b0");
}

TEST(ScriptExpect, APickThatHitNothingFailsEveryHitField) {
    EXPECT_TRUE(check_answer(Json::parse(R"({"hit": false})"), ExpectTarget::Pick, MISSED).empty());
    const auto m = check_answer(Json::parse(R"({"hit": true, "hit.instance": "b0"})"),
                                ExpectTarget::Pick, MISSED);
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].field, "hit");
    EXPECT_EQ(m[0].expected, "true");
    EXPECT_EQ(m[0].actual, "false");
    EXPECT_EQ(m[1].actual, "(no hit)");
    EXPECT_EQ(m[1].note, "nothing was hit");
    const auto hit = check_answer(Json::parse(R"({"hit": false})"), ExpectTarget::Pick, PICKED);
    ASSERT_EQ(hit.size(), 1u);
    EXPECT_EQ(hit[0].actual, "true");
}

TEST(ScriptExpect, AListChecksTheCountAndTheExactSetOfIds) {
    EXPECT_TRUE(check_answer(Json::parse(R"({"count": 3, "ids": ["c", "b", "a"], "version": 9})"),
                             ExpectTarget::List, LISTED)
                    .empty());
    const auto m = check_answer(Json::parse(R"({"count": {"min": 4}, "ids": ["a", "b", "d"]})"),
                                ExpectTarget::List, LISTED);
    ASSERT_EQ(m.size(), 2u);
    EXPECT_EQ(m[0].field, "count");
    EXPECT_EQ(m[0].actual, "3");
    EXPECT_EQ(m[1].field, "ids");
    EXPECT_EQ(m[1].note, "missing: d; unexpected: c");
}

TEST(ScriptExpect, EachTargetAcceptsOnlyItsOwnFields) {
    const auto error = [](const char* expect, ExpectTarget target) {
        auto e = Expectation::compile(Json::parse(expect), {}, true, target);
        return e.has_value() ? std::string("(compiled)") : e.error().message;
    };
    EXPECT_NE(error(R"({"tlas": "none"})", ExpectTarget::Pick).find("unknown member \"tlas\""),
              std::string::npos);
    EXPECT_NE(error(R"({"hit.instance": "a"})", ExpectTarget::List)
                  .find("unknown member \"hit.instance\""),
              std::string::npos);
    EXPECT_NE(error(R"({"count": 1})", ExpectTarget::Report).find("unknown member \"count\""),
              std::string::npos);
    EXPECT_NE(error(R"({"hit": "b0"})", ExpectTarget::Pick).find("expected true"),
              std::string::npos);
    EXPECT_NE(error(R"({"hit.mesh": 3})", ExpectTarget::Pick).find("expected an id"),
              std::string::npos);
    EXPECT_NE(error(R"({"ids": "a"})", ExpectTarget::List).find("expected an array of ids"),
              std::string::npos);
}

}  // namespace
}  // namespace strata::cli

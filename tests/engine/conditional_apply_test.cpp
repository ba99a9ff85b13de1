// Engine::apply with an expected version: the If-Match precondition of POST /v1/edits, checked
// under the same lock as the apply.

#include <atomic>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/engine/test_util.h"

namespace strata {
namespace {

EditBatch one_material(const std::string& id) {
    EditBatch b;
    b.edits.emplace_back(AddMaterial{id, {}});
    return b;
}

TEST(ConditionalApply, AppliesWhenTheVersionMatches) {
    auto engine = test::make_engine();
    auto r = engine->apply(one_material("a"), uint64_t{0});
    ASSERT_TRUE(r.has_value()) << r.error().describe();
    EXPECT_EQ(r.value().version, 1u);
    EXPECT_EQ(r.value().applied, 1u);
}

TEST(ConditionalApply, RefusesAnotherVersionAndChangesNothing) {
    auto engine = test::make_engine();
    test::apply_ok(*engine, AddMaterial{"a", {}});
    auto r = engine->apply(one_material("b"), uint64_t{0});
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::VersionMismatch);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 1u);
    EXPECT_TRUE(engine->read([](const Scene& s) { return s.find_material("b").is_null(); }));
}

TEST(ConditionalApply, WithoutAnExpectedVersionAlwaysApplies) {
    auto engine = test::make_engine();
    test::apply_ok(*engine, AddMaterial{"a", {}});
    EXPECT_TRUE(engine->apply(one_material("b"), std::nullopt).has_value());
}

TEST(ConditionalApply, OnlyOneOfManyRacingWritersWithTheSameVersionWins) {
    auto engine = test::make_engine();
    std::atomic<int> wins{0};
    std::vector<std::thread> writers;
    for (int t = 0; t < 8; ++t) {
        writers.emplace_back([&, t] {
            if (engine->apply(one_material("m" + std::to_string(t)), uint64_t{0}).has_value())
                ++wins;
        });
    }
    for (auto& w : writers) w.join();
    EXPECT_EQ(wins.load(), 1);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 1u);
}

TEST(Validate, AcceptsAGoodBatchAndLeavesTheSceneAsItWas) {
    auto engine = test::make_engine();
    test::apply_ok(*engine, AddMaterial{"a", {}});
    ASSERT_TRUE(engine->commit().has_value());
    ASSERT_TRUE(engine->validate(one_material("b"), 1).has_value());
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 1u);
    EXPECT_TRUE(engine->read([](const Scene& s) { return s.find_material("b").is_null(); }));
    EXPECT_TRUE(engine->read([](const Scene& s) { return s.changes().empty(); }));
    // The validated batch then applies for real.
    EXPECT_TRUE(engine->apply(one_material("b"), uint64_t{1}).has_value());
}

TEST(Validate, AnswersTheRuleErrorOfABadBatch) {
    auto engine = test::make_engine();
    test::apply_ok(*engine, AddMaterial{"a", {}});
    auto r = engine->validate(one_material("a"), 1);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::DuplicateId);
    EXPECT_EQ(r.error().edit_index, 0u);
}

TEST(Validate, RefusesAnotherVersion) {
    auto engine = test::make_engine();
    auto r = engine->validate(one_material("a"), 3);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::VersionMismatch);
}

}  // namespace
}  // namespace strata

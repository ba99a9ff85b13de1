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

}  // namespace
}  // namespace strata

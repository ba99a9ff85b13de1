// Engine::set_commit_listener: every commit's report, in order, on the committing thread; none
// once the listener is removed.

#include <thread>
#include <vector>

#include "tests/engine/test_util.h"

namespace strata::test {
namespace {

TEST(CommitListener, EveryCommitsReportReachesTheListenerInOrderOnTheCommittingThread) {
    auto engine = make_engine();
    std::vector<RebuildReport> heard;
    std::vector<std::thread::id> threads;
    engine->set_commit_listener([&](const RebuildReport& r) {
        heard.push_back(r);
        threads.push_back(std::this_thread::get_id());
    });
    apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, 16)), instance_edit("a", "ball"));
    commit_ok(*engine);
    apply_ok(*engine, instance_edit("b", "ball", Vec3(3, 0, 0)));
    commit_ok(*engine);
    commit_ok(*engine);  // nothing new: still a commit, still reported
    ASSERT_EQ(heard.size(), 3u);
    EXPECT_EQ(heard[0].version, 1u);
    EXPECT_EQ(heard[0].blas_rebuilds, 1u);
    EXPECT_EQ(heard[1].version, 2u);
    EXPECT_EQ(heard[1].blas_rebuilds, 0u);
    EXPECT_EQ(heard[2].version, 2u);
    EXPECT_TRUE(heard[2].no_accel_work());
    for (const auto& t : threads) EXPECT_EQ(t, std::this_thread::get_id());
    EXPECT_EQ(engine->counters().commits, 3u);
}

TEST(CommitListener, ARemovedListenerHearsNothingMore) {
    auto engine = make_engine();
    int calls = 0;
    engine->set_commit_listener([&](const RebuildReport&) { ++calls; });
    apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, 16)), instance_edit("a", "ball"));
    commit_ok(*engine);
    engine->set_commit_listener(nullptr);
    apply_ok(*engine, instance_edit("b", "ball", Vec3(3, 0, 0)));
    commit_ok(*engine);
    EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace strata::test

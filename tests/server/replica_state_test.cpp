// What a replica's reader, writer and snapshotter share (server/replica/replica_state.h), without
// Redis: versions and lag, stopping loudly, and the waits the write path makes.

#include <thread>

#include <gtest/gtest.h>

#include "server/replica/replica_state.h"

namespace strata::replica {
namespace {

using std::chrono::milliseconds;

TEST(ReplicaState, TheLagIsWhatTheLogHasAndThisReplicaHasNotApplied) {
    ReplicaState state("redis://127.0.0.1:6379/strata", 4);
    state.raise_log_version(7);
    state.raise_log_version(5);  // never lowered
    state.entry_waiting(unix_ms() - 2000);
    ReplicaStatus s = state.status();
    EXPECT_EQ(s.applied_version, 4u);
    EXPECT_EQ(s.log_version, 7u);
    EXPECT_EQ(s.lag_entries, 3u);
    EXPECT_GE(s.lag_seconds, 1.5);
    state.applied_entry(7, 0);
    s = state.status();
    EXPECT_EQ(s.lag_entries, 0u);
    EXPECT_EQ(s.lag_seconds, 0.0);
    EXPECT_EQ(s.entries_applied, 1u);
    EXPECT_EQ(s.log, "redis://127.0.0.1:6379/strata");
}

TEST(ReplicaState, ALogBehindTheAppliedVersionStopsItForGoodSayingWhy) {
    ReplicaState state("log", 10);
    EXPECT_TRUE(state.check_not_behind(10).has_value());
    EXPECT_FALSE(state.stopped());
    const Status behind = state.check_not_behind(3);
    ASSERT_FALSE(behind.has_value());
    EXPECT_EQ(behind.error().code, ErrorCode::Storage);
    EXPECT_NE(behind.error().message.find("ends at version 3, behind this replica's version 10"),
              std::string::npos)
        << behind.error().message;
    EXPECT_TRUE(state.stopped());
    state.stop_loudly("a second reason");  // the first one stays
    EXPECT_NE(state.status().stop_reason.find("ends at version 3"), std::string::npos);
    EXPECT_FALSE(state.wait_applied(11, milliseconds(1000))) << "a stopped replica waits no more";
}

TEST(ReplicaState, WritesWaitForTheReaderToApplyTheirVersion) {
    ReplicaState state("log", 1);
    EXPECT_FALSE(state.wait_applied(2, milliseconds(10)));
    std::thread reader([&] {
        std::this_thread::sleep_for(milliseconds(20));
        state.applied_entry(2, 0);
    });
    EXPECT_TRUE(state.wait_applied(2, milliseconds(10000)));
    reader.join();
    EXPECT_FALSE(state.wait_joined(Clock::now() + milliseconds(10)).has_value());
    state.mark_joined();
    EXPECT_TRUE(state.wait_joined(Clock::now()).has_value());
    state.count(&ReplicaStatus::appends, 2);
    EXPECT_EQ(state.status().appends, 2u);
    state.shut_down();
    EXPECT_FALSE(state.sleep_for(milliseconds(1000)));
}

}  // namespace
}  // namespace strata::replica

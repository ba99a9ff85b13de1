// The front end's admission counts and its held reads (server/client_quota.h,
// server/waiting_reads.h), without sockets: the limits, the order reads are released in, and
// what a client that leaves gives back.

#include <gtest/gtest.h>

#include "server/client_quota.h"
#include "server/waiting_reads.h"

namespace strata::server {
namespace {

using Clock = WaitingReads::Clock;
using std::chrono::milliseconds;

TEST(ClientQuota, EachClientAndEveryoneTogetherStayUnderTheirLimits) {
    ClientQuota q(3, 2);
    EXPECT_TRUE(q.admits("a"));
    q.take("a");
    q.take("a");
    EXPECT_FALSE(q.admits("a")) << "a holds its share";
    EXPECT_TRUE(q.admits("b"));
    q.take("b");
    EXPECT_FALSE(q.admits("c")) << "everyone together holds the total";
    q.give_back("a");
    EXPECT_TRUE(q.admits("a"));
    EXPECT_TRUE(q.admits("c"));
    EXPECT_EQ(q.held("a"), 1u);
    EXPECT_EQ(q.total(), 2u);
    q.give_back("a");
    q.give_back("b");
    EXPECT_EQ(q.held("a"), 0u);
    EXPECT_EQ(q.total(), 0u);
}

/// Every scene at `version`.
WaitingReads::VersionOf at(uint64_t version) {
    return [version](std::string_view) { return version; };
}

WaitingReads::Waiter waiter(uint64_t conn, std::string client, uint64_t wanted,
                            Clock::time_point deadline, std::string scene = {}) {
    WaitingReads::Waiter w;
    w.conn = conn;
    w.scene = std::move(scene);
    w.client = std::move(client);
    w.wanted = wanted;
    w.deadline = deadline;
    w.request.http.path = "/v1/scene/" + std::to_string(conn);
    return w;
}

TEST(WaitingReads, ReadsLeaveOldestFirstWhenTheirVersionArrivesOrTheirWaitEnds) {
    WaitingReads w(10, 10);
    const Clock::time_point now = Clock::now();
    w.park(waiter(1, "a", 5, now + milliseconds(100)));
    w.park(waiter(2, "a", 3, now + milliseconds(100)));
    w.park(waiter(3, "b", 9, now + milliseconds(10)));
    EXPECT_TRUE(w.take_due(at(2), now, false).empty());
    auto due = w.take_due(at(5), now, false);
    ASSERT_EQ(due.size(), 2u);
    EXPECT_EQ(due[0].conn, 1u);
    EXPECT_EQ(due[1].conn, 2u);
    EXPECT_EQ(due[1].request.http.path, "/v1/scene/2") << "the request comes back with it";
    due = w.take_due(at(5), now + milliseconds(10), false);
    ASSERT_EQ(due.size(), 1u) << "its wait is over, its version has not come";
    EXPECT_EQ(due[0].conn, 3u);
    EXPECT_TRUE(w.empty());
}

TEST(WaitingReads, EachReadWaitsForItsOwnScenesVersion) {
    WaitingReads w(10, 10);
    const Clock::time_point now = Clock::now();
    w.park(waiter(1, "a", 4, now + milliseconds(100)));
    w.park(waiter(2, "a", 4, now + milliseconds(100), "city"));
    const auto versions = [](uint64_t main, uint64_t city) -> WaitingReads::VersionOf {
        return [=](std::string_view scene) { return scene == "city" ? city : main; };
    };
    auto due = w.take_due(versions(4, 3), now, false);
    ASSERT_EQ(due.size(), 1u);
    EXPECT_EQ(due[0].conn, 1u);
    EXPECT_TRUE(w.take_due(versions(9, 3), now, false).empty()) << "another scene moved";
    due = w.take_due(versions(9, 4), now, false);
    ASSERT_EQ(due.size(), 1u);
    EXPECT_EQ(due[0].scene, "city");
}

TEST(WaitingReads, ADrainReleasesEveryRead) {
    WaitingReads w(10, 10);
    const Clock::time_point now = Clock::now();
    w.park(waiter(1, "a", 50, now + milliseconds(1000)));
    w.park(waiter(2, "b", 60, now + milliseconds(1000)));
    EXPECT_EQ(w.take_due(at(1), now, true).size(), 2u);
    EXPECT_TRUE(w.admits("a"));
}

TEST(WaitingReads, TheLimitsHoldAndAClientThatLeavesGivesItsShareBack) {
    WaitingReads w(3, 2);
    const Clock::time_point later = Clock::now() + milliseconds(1000);
    w.park(waiter(1, "a", 9, later));
    w.park(waiter(2, "a", 9, later));
    EXPECT_FALSE(w.admits("a"));
    EXPECT_NE(w.refusal("a").find("2 from this client, 2 in all"), std::string::npos)
        << w.refusal("a");
    EXPECT_NE(w.refusal("a").find("--max-waiting-reads-per-client 2"), std::string::npos);
    w.park(waiter(3, "b", 9, later));
    EXPECT_FALSE(w.admits("c")) << "3 in all";
    w.forget(1);
    w.forget(42);  // not a waiter: nothing changes
    EXPECT_TRUE(w.admits("a"));
    EXPECT_EQ(w.size(), 2u);
}

}  // namespace
}  // namespace strata::server

// GET /v1/events' producer (server/commit_events.h) without a server: which commits become
// events, in what order, what a full queue drops, and what stopping ends.

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/commit_events.h"

namespace strata::server {
namespace {

RebuildReport commit(uint64_t version) {
    RebuildReport r;
    r.version = version;
    return r;
}

/// The parts a channel holds, in order.
std::vector<std::string> drain(StreamChannel& c) {
    std::vector<std::string> out;
    while (StreamChannel::Part p = c.take()) {
        out.push_back(*p);
        c.written();
    }
    return out;
}

TEST(CommitEvents, EachNewCommitIsOneEventInOrderAndOldVersionsAreNone) {
    int pokes = 0;
    CommitEvents events(3, [&] { ++pokes; });
    events.on_commit(commit(4));  // no client yet: remembered, not queued
    auto channel = events.subscribe();
    ASSERT_NE(channel, nullptr);
    events.on_commit(commit(3));  // at or below what was reported: no event
    events.on_commit(commit(5));
    events.on_commit(commit(6));
    events.publish(CommitEvents::Clock::now());
    const std::vector<std::string> parts = drain(*channel);
    ASSERT_EQ(parts.size(), 3u) << "two events and the first keep-alive";
    EXPECT_EQ(parts[0].rfind("id: 5\nevent: commit\ndata: {", 0), 0u) << parts[0];
    EXPECT_EQ(parts[1].rfind("id: 6\n", 0), 0u) << parts[1];
    EXPECT_EQ(parts[2], ": keep-alive\n\n");
    EXPECT_EQ(events.last_commit()->version, 6u);
    EXPECT_GE(pokes, 3) << "the subscription and each queued event wake the publisher";
    const CommitEvents::Stats s = events.stats();
    EXPECT_EQ(s.clients, 1u);
    EXPECT_EQ(s.events, 2u);
    EXPECT_EQ(s.events_dropped, 0u);
}

TEST(CommitEvents, AFullQueueDropsTheOldestAndCountsThem) {
    CommitEvents events(0, [] {});
    auto channel = events.subscribe();
    for (uint64_t v = 1; v <= 1030; ++v) events.on_commit(commit(v));
    EXPECT_EQ(events.stats().events_dropped, 6u);
    events.publish(CommitEvents::Clock::now());
    EXPECT_EQ(events.stats().events, 1024u);
}

TEST(CommitEvents, StoppingEndsTheStreamsAndRefusesNewOnes) {
    CommitEvents events(0, [] {});
    auto channel = events.subscribe();
    events.stop();
    EXPECT_TRUE(channel->ended());
    EXPECT_EQ(events.subscribe(), nullptr);
    events.on_commit(commit(1));
    EXPECT_FALSE(events.last_commit().has_value());
    EXPECT_FALSE(events.has_clients());
}

}  // namespace
}  // namespace strata::server

// The replica's pieces that need no Redis: --log URL parsing and the log entry format.

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "server/replica/log_entry.h"
#include "server/replica/redis_url.h"

namespace strata::replica {
namespace {

TEST(RedisUrl, ParsesHostPortAndStream) {
    auto u = parse_redis_url("redis://127.0.0.1:6380/strata-log");
    ASSERT_TRUE(u.has_value()) << u.error().message;
    EXPECT_EQ(u->host, "127.0.0.1");
    EXPECT_EQ(u->port, 6380);
    EXPECT_EQ(u->stream, "strata-log");
    EXPECT_EQ(u->version_key(), "strata-log:version");
    EXPECT_EQ(u->snapshot_key(), "strata-log:snapshot");
    EXPECT_EQ(u->describe(), "redis://127.0.0.1:6380/strata-log");
}

TEST(RedisUrl, DefaultsThePortAndTakesNamesAndIpv6) {
    auto named = parse_redis_url("redis://redis/edits");
    ASSERT_TRUE(named.has_value());
    EXPECT_EQ(named->host, "redis");
    EXPECT_EQ(named->port, 6379);
    auto v6 = parse_redis_url("redis://[::1]:7000/edits");
    ASSERT_TRUE(v6.has_value()) << v6.error().message;
    EXPECT_EQ(v6->host, "::1");
    EXPECT_EQ(v6->port, 7000);
    EXPECT_EQ(v6->describe(), "redis://[::1]:7000/edits");
}

TEST(RedisUrl, RefusesWhatItCannotUseAndSaysWhichPart) {
    const std::pair<const char*, const char*> cases[] = {
        {"http://h:1/s", "scheme"},
        {"redis://h:1", "stream name is missing"},
        {"redis://h:1/", "stream name is missing"},
        {"redis://:1/s", "host is missing"},
        {"redis://h:0/s", "port"},
        {"redis://h:70000/s", "port"},
        {"redis://h:x/s", "port"},
        {"redis://h:/s", "port"},
        {"redis://user:pw@h:1/s", "credentials"},
        {"redis://h:1/a/b", "one path segment"},
        {"redis://h:1/a b", "one path segment"},
        {"redis://h h:1/s", "host"},
        {"redis://[::1/s", "']'"},
    };
    for (const auto& [url, why] : cases) {
        auto u = parse_redis_url(url);
        ASSERT_FALSE(u.has_value()) << url;
        EXPECT_EQ(u.error().code, ErrorCode::InvalidArgument);
        EXPECT_NE(u.error().message.find(why), std::string::npos)
            << url << ": " << u.error().message;
    }
}

EditBatch sample_batch() {
    EditBatch b;
    b.edits.emplace_back(AddMaterial{"m", {}});
    b.edits.emplace_back(AddMaterial{"n", {}});
    return b;
}

TEST(LogEntry, RoundTripsABatchAndItsVersion) {
    const std::string bytes = encode_entry(sample_batch(), 42);
    auto entry = decode_entry(bytes);
    ASSERT_TRUE(entry.has_value()) << entry.error().message;
    EXPECT_EQ(entry->version, 42u);
    auto batch = durable::decode_batch(entry->payload);
    ASSERT_TRUE(batch.has_value()) << batch.error().describe();
    ASSERT_EQ(batch->edits.size(), 2u);
    EXPECT_EQ(std::get<AddMaterial>(batch->edits[1]).id, "n");
    EXPECT_EQ(entry_id(42), "42-0");
}

TEST(LogEntry, RestampingChangesOnlyTheVersion) {
    const std::string original = encode_entry(sample_batch(), 0);
    const std::string stamped = restamp_entry(original, 7);
    EXPECT_EQ(stamped, encode_entry(sample_batch(), 7));
    auto entry = decode_entry(stamped);
    ASSERT_TRUE(entry.has_value());
    EXPECT_EQ(entry->version, 7u);
}

TEST(LogEntry, RefusesDamagedAndTruncatedEntries) {
    std::string bytes = encode_entry(sample_batch(), 3);
    std::string flipped = bytes;
    flipped.back() ^= 0x20;
    auto damaged = decode_entry(flipped);
    ASSERT_FALSE(damaged.has_value());
    EXPECT_NE(damaged.error().message.find("checksum"), std::string::npos);

    std::string other_version = bytes;
    other_version[8] = 4;  // the version is covered by the checksum
    EXPECT_FALSE(decode_entry(other_version).has_value());

    auto truncated = decode_entry(std::string_view(bytes).substr(0, bytes.size() - 1));
    ASSERT_FALSE(truncated.has_value());
    EXPECT_NE(truncated.error().message.find("follow"), std::string::npos);
    EXPECT_FALSE(decode_entry("short").has_value());
}

}  // namespace
}  // namespace strata::replica

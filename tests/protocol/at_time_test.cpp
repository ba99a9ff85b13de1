// at_time (protocol/api.h): RFC 3339 times, and the version the history says was live then.

#include <thread>

#include <gtest/gtest.h>

#include "protocol/api.h"

namespace strata::protocol {
namespace {

TEST(AtTime, Rfc3339TimesAreReadWithTheirOffsetsAndFractions) {
    EXPECT_EQ(parse_rfc3339("1970-01-01T00:00:00Z"), 0);
    EXPECT_EQ(parse_rfc3339("2026-11-27T17:02:03.456Z"), 1795798923456);
    EXPECT_EQ(parse_rfc3339("2026-11-27T18:02:03.456+01:00"), 1795798923456);
    EXPECT_EQ(parse_rfc3339("2026-11-27t12:02:03.4567-05:00"), 1795798923456);
    EXPECT_EQ(parse_rfc3339("2026-11-27T17:02:03.5z"), 1795798923500);
    for (const char* bad : {"", "2026-11-27", "2026-11-27T17:02:03", "2026-13-01T00:00:00Z",
                            "2026-02-31T00:00:00Z", "2026-11-27T17:02:03.Z",
                            "2026-11-27T17:02:03Z ", "2026-11-27T24:00:00Z",
                            "2026-11-27T17:02:03+1:00", "now", "-3600"})
        EXPECT_FALSE(parse_rfc3339(bad).has_value()) << bad;
}

std::string stamp(int64_t ms) {
    const std::time_t s = std::time_t(ms / 1000);
    std::tm utc{};
    gmtime_r(&s, &utc);
    char text[40];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
    return std::string(text) + "." + std::to_string(1000 + ms % 1000).substr(1) + "Z";
}

int64_t now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

TEST(AtTime, TheNewestVersionMadeByThenIsChosen) {
    auto engine = Engine::create();
    ASSERT_TRUE(engine.has_value());
    Engine& e = *engine.value();
    const int64_t before_any = now_ms() - 1000;
    EXPECT_FALSE(version_at_time(e, stamp(before_any)).has_value());  // no history yet
    EditBatch one;
    one.edits.emplace_back(SetCamera{Vec3(0, 1, 5), std::nullopt, std::nullopt, std::nullopt});
    ASSERT_TRUE(e.apply(std::move(one)).has_value());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const int64_t between = now_ms();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    EditBatch two;
    two.edits.emplace_back(SetCamera{Vec3(0, 2, 5), std::nullopt, std::nullopt, std::nullopt});
    ASSERT_TRUE(e.apply(std::move(two)).has_value());
    EXPECT_EQ(version_at_time(e, stamp(between)).value(), 1u);
    EXPECT_EQ(version_at_time(e, stamp(now_ms() + 60000)).value(), 2u);
    const auto early = version_at_time(e, stamp(before_any));
    ASSERT_FALSE(early.has_value());
    EXPECT_EQ(early.error().type, ProblemType::NotFound);
    EXPECT_NE(early.error().detail.find("oldest version the history lists, 1"),
              std::string::npos)
        << early.error().detail;
    EXPECT_EQ(version_at_time(e, "yesterday").error().type, ProblemType::InvalidRequest);
}

}  // namespace
}  // namespace strata::protocol

// Request targets: one normalised spelling per path, ids with reserved characters kept as one
// segment, and a strict query.

#include <gtest/gtest.h>

#include "server/request_target.h"

namespace strata::server {
namespace {

using protocol::Problem;

RequestTarget target_ok(std::string_view raw) {
    auto t = parse_request_target(raw);
    if (auto* e = std::get_if<Problem>(&t)) ADD_FAILURE() << raw << ": " << e->detail;
    return std::holds_alternative<RequestTarget>(t) ? std::get<RequestTarget>(t) : RequestTarget{};
}

std::string target_error(std::string_view raw) {
    auto t = parse_request_target(raw);
    EXPECT_TRUE(std::holds_alternative<Problem>(t)) << raw;
    return std::holds_alternative<Problem>(t) ? std::get<Problem>(t).detail : "";
}

TEST(RequestTarget, UnreservedEscapesAreDecodedAndOthersKeptUpperCase) {
    EXPECT_EQ(target_ok("/v1/%73cene").path, "/v1/scene");
    EXPECT_EQ(target_ok("/v1/scene/instances/%2fWorld%2Fa").path,
              "/v1/scene/instances/%2FWorld%2Fa");
    EXPECT_EQ(target_ok("/%ff").path, "/%FF");
    EXPECT_EQ(target_ok("http://example.com:7070/v1/scene?x=1").path, "/v1/scene");
    EXPECT_EQ(target_ok("HTTP://example.com").path, "/");
}

TEST(RequestTarget, APathSegmentDecodesToTheIdItNames) {
    EXPECT_EQ(decode_path_segment("%2FWorld%2FLooks%2Fred"), "/World/Looks/red");
    EXPECT_EQ(decode_path_segment("caf%C3%A9"), "caf\xC3\xA9");
    EXPECT_EQ(decode_path_segment("a+b"), "a+b");
}

TEST(RequestTarget, TheQueryIsDecodedStrictly) {
    const RequestTarget t = target_ok("/v1/render?width=8&eye=1%2C2,3&&aovs=&name=a+b");
    ASSERT_EQ(t.query.size(), 4u);
    EXPECT_EQ(t.query[1].first, "eye");
    EXPECT_EQ(t.query[1].second, "1,2,3");
    EXPECT_EQ(t.query[2].second, "");
    EXPECT_EQ(t.query[3].second, "a b");
    EXPECT_NE(target_error("/v1/render?width=8&width=8").find("more than once"), std::string::npos);
    EXPECT_NE(target_error("/v1/render?format=%ff").find("not valid UTF-8"), std::string::npos);
    EXPECT_NE(target_error("/v1/render?format=%0a").find("control character"), std::string::npos);
    EXPECT_NE(target_error("/v1/render?x=%zz").find("percent-escape"), std::string::npos);
    EXPECT_NE(target_error("/v1/render?=5").find("no name"), std::string::npos);
}

TEST(RequestTarget, MalformedTargetsAreRefused) {
    for (const char* bad : {"*", "v1/scene", "/a%2", "/a%g0", "/a#frag", "http://host?x=1"})
        target_error(bad);
}

}  // namespace
}  // namespace strata::server

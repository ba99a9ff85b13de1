// The front end's HTTP/1.1 reader: what it accepts, and every class of ambiguous framing it
// refuses (the request-smuggling class), with the status it answers.

#include <optional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "server/http_parser.h"

namespace strata::server {
namespace {

using protocol::Problem;

const HttpLimits LIMITS{};

RequestHead parse_ok(const std::string& head) {
    auto r = parse_request_head(head, LIMITS);
    if (auto* e = std::get_if<Problem>(&r)) ADD_FAILURE() << head << ": " << e->detail;
    return std::holds_alternative<RequestHead>(r) ? std::get<RequestHead>(r) : RequestHead{};
}

Problem parse_error(const std::string& head, const HttpLimits& limits = LIMITS) {
    auto r = parse_request_head(head, limits);
    EXPECT_TRUE(std::holds_alternative<Problem>(r)) << head;
    return std::holds_alternative<Problem>(r) ? std::get<Problem>(r) : Problem{};
}

TEST(HttpHead, AnOrdinaryRequestIsReadWithItsFraming) {
    const RequestHead h = parse_ok(
        "POST /v1/edits?x=1 HTTP/1.1\r\nHost: a\r\nContent-Length: 12\r\n"
        "Authorization:  Bearer t  \r\n\r\n");
    EXPECT_EQ(h.method, "POST");
    EXPECT_EQ(h.target, "/v1/edits?x=1");
    EXPECT_EQ(h.framing, BodyFraming::Length);
    EXPECT_EQ(h.content_length, 12u);
    EXPECT_TRUE(h.keep_alive);
    ASSERT_NE(h.header("authorization"), nullptr);
    EXPECT_EQ(*h.header("AUTHORIZATION"), "Bearer t");
}

TEST(HttpHead, BareLfLinesLeadingEmptyLinesAndHttp10AreAccepted) {
    const RequestHead h = parse_ok("\r\n\nGET / HTTP/1.0\nConnection: keep-alive\n\n");
    EXPECT_EQ(h.minor_version, 0);
    EXPECT_TRUE(h.keep_alive);
    EXPECT_FALSE(parse_ok("GET / HTTP/1.0\r\n\r\n").keep_alive);
    EXPECT_FALSE(parse_ok("GET / HTTP/1.1\r\nHost: a\r\nConnection: te, Close\r\n\r\n").keep_alive);
    EXPECT_EQ(parse_ok("POST / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: Chunked\r\n\r\n").framing,
              BodyFraming::Chunked);
}

struct Refusal {
    const char* name;
    const char* head;
    int status;
};

class HttpRefusal : public ::testing::TestWithParam<Refusal> {};

TEST_P(HttpRefusal, IsAnsweredWithItsStatus) {
    EXPECT_EQ(parse_error(GetParam().head).status, GetParam().status) << GetParam().name;
}

INSTANTIATE_TEST_SUITE_P(
    Smuggling, HttpRefusal,
    ::testing::Values(
        Refusal{"ConflictingLengths",
                "POST / HTTP/1.1\r\nHost: a\r\nContent-Length: 5\r\nContent-Length: 6\r\n\r\n",
                400},
        Refusal{"LengthList", "POST / HTTP/1.1\r\nHost: a\r\nContent-Length: 5, 5\r\n\r\n", 400},
        Refusal{"SignedLength", "POST / HTTP/1.1\r\nHost: a\r\nContent-Length: +5\r\n\r\n", 400},
        Refusal{"HugeLength",
                "POST / HTTP/1.1\r\nHost: a\r\nContent-Length: 99999999999999999999\r\n\r\n", 400},
        Refusal{
            "LengthAndChunked",
            "POST / HTTP/1.1\r\nHost: a\r\nContent-Length: 5\r\nTransfer-Encoding: chunked\r\n\r\n",
            400},
        Refusal{"UnknownTransferCoding",
                "POST / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: gzip\r\n\r\n", 400},
        Refusal{"ChunkedNotAlone",
                "POST / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: gzip, chunked\r\n\r\n", 400},
        Refusal{"ChunkedTwice",
                "POST / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: chunked\r\nTransfer-Encoding: "
                "chunked\r\n\r\n",
                400},
        Refusal{"ChunkedInHttp10", "POST / HTTP/1.0\r\nTransfer-Encoding: chunked\r\n\r\n", 400},
        Refusal{"NoColon", "GET / HTTP/1.1\r\nHost: a\r\nJunk line\r\n\r\n", 400},
        Refusal{"SpaceBeforeColon", "GET / HTTP/1.1\r\nHost: a\r\nContent-Length : 5\r\n\r\n", 400},
        Refusal{"ObsFold", "GET / HTTP/1.1\r\nHost: a\r\nX: a\r\n  b\r\n\r\n", 400},
        Refusal{"BareCr", "GET / HTTP/1.1\r\nHost: a\r\nX: a\rb\r\n\r\n", 400},
        Refusal{"BareCrInRequestLine", "GET /\r HTTP/1.1\r\nHost: a\r\n\r\n", 400},
        Refusal{"NoHost", "GET / HTTP/1.1\r\n\r\n", 400},
        Refusal{"TwoHosts", "GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n", 400},
        Refusal{"TwoAuthorizations",
                "GET / HTTP/1.1\r\nHost: a\r\nAuthorization: x\r\nAuthorization: y\r\n\r\n", 400},
        Refusal{"DoubleSpace", "GET  / HTTP/1.1\r\nHost: a\r\n\r\n", 400},
        Refusal{"SpaceInTarget", "GET /a b HTTP/1.1\r\nHost: a\r\n\r\n", 400},
        Refusal{"NonAsciiTarget", "GET /\xFF HTTP/1.1\r\nHost: a\r\n\r\n", 400},
        Refusal{"BadVersion", "GET / HTTP/x\r\nHost: a\r\n\r\n", 400},
        Refusal{"Http2Preface", "PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n", 505},
        Refusal{"UnknownMethod", "BREW / HTTP/1.1\r\nHost: a\r\n\r\n", 501},
        Refusal{"Trace", "TRACE / HTTP/1.1\r\nHost: a\r\n\r\n", 501},
        Refusal{"UnknownExpectation", "POST / HTTP/1.1\r\nHost: a\r\nExpect: 200-ok\r\n\r\n", 417}),
    [](const auto& test) { return std::string(test.param.name); });

TEST(HttpHead, NulInAValueIsRefused) {
    // Built with an explicit length: a C string would end at the NUL.
    const std::string head("GET / HTTP/1.1\r\nHost: a\r\nX: a\0b\r\n\r\n", 35);
    EXPECT_EQ(parse_error(head).status, 400);
}

TEST(HttpHead, HeaderCountSizeAndTargetLengthHaveLimits) {
    std::string many = "GET / HTTP/1.1\r\nHost: a\r\n";
    for (int i = 0; i < 100; ++i) many += "X-" + std::to_string(i) + ": v\r\n";
    EXPECT_EQ(parse_error(many + "\r\n").status, 431);
    HttpLimits small;
    small.max_head_bytes = 64;
    EXPECT_EQ(
        parse_error("GET / HTTP/1.1\r\nHost: a\r\nX: " + std::string(64, 'v') + "\r\n\r\n", small)
            .status,
        431);
    EXPECT_EQ(parse_error("GET /" + std::string(9000, 'a') + " HTTP/1.1\r\nHost: a\r\n\r\n").status,
              414);
    EXPECT_EQ(parse_error("GET / HTTP/1.1\r\nHost: a\r\nX: " + std::string(9000, 'v') + "\r\n\r\n")
                  .status,
              431);
}

TEST(HttpHead, TheEndOfAHeadIsFoundOnceWhateverTheSplit) {
    const std::string head = "\r\nGET / HTTP/1.1\r\nHost: a\r\n\r\nNEXT";
    EXPECT_EQ(find_head_end(head), head.size() - 4);
    // Fed one byte at a time, each call looking only at what is new.
    std::size_t searched = 0, end = std::string::npos;
    for (std::size_t n = 1; n <= head.size() && end == std::string::npos; ++n) {
        end = find_head_end(std::string_view(head).substr(0, n), searched);
        searched = n;
    }
    EXPECT_EQ(end, head.size() - 4);
    EXPECT_EQ(find_head_end("GET / HTTP/1.1\nHost: a\n\n"), 24u);
    EXPECT_EQ(find_head_end("\r\n\r\n"), std::string::npos);
    EXPECT_EQ(find_head_end("GET / HTTP/1.1\r\nHost: a\r\n"), std::string::npos);
}

/// Feeds `wire` to a decoder `step` bytes at a time; returns the body, and the error if any.
std::string decode_chunked(const std::string& wire, std::size_t step, uint64_t max = 1 << 20,
                           std::optional<Problem>* error = nullptr) {
    ChunkedDecoder decoder(max);
    std::string body, pending;
    for (std::size_t pos = 0; pos < wire.size() && !decoder.done() && !decoder.error();
         pos += step) {
        pending += wire.substr(pos, step);
        pending.erase(0, decoder.feed(pending, body));
    }
    EXPECT_TRUE(decoder.done() || decoder.error()) << wire;
    if (error && decoder.error()) *error = *decoder.error();
    return body;
}

TEST(ChunkedBody, DecodesWithExtensionsAndTrailersWhateverTheSplit) {
    const std::string wire = "5;ext=1\r\nhello\r\n7\r\n, world\r\n0\r\nX-Trailer: t\r\n\r\n";
    for (std::size_t step : {1, 2, 3, 7, 1000})
        EXPECT_EQ(decode_chunked(wire, step), "hello, world");
    EXPECT_EQ(decode_chunked("A\nabcdefghij\n0\n\n", 1), "abcdefghij");
}

TEST(ChunkedBody, MalformedOrOversizedBodiesAreRefused) {
    for (const char* bad :
         {"z\r\nx\r\n0\r\n\r\n", "5\r\nhello!\r\n0\r\n\r\n", "-1\r\n\r\n", "ffffffffffffffffff\r\n",
          "5\r\nhello\r0\r\n\r\n", "0\r\nbad trailer\r\n\r\n", "0\r\n folded: x\r\n\r\n"}) {
        std::optional<Problem> e;
        decode_chunked(bad, 1, 1 << 20, &e);
        ASSERT_TRUE(e.has_value()) << bad;
        EXPECT_EQ(e->status, 400) << bad;
    }
    std::optional<Problem> e;
    decode_chunked("400\r\n" + std::string(1024, 'x') + "\r\n0\r\n\r\n", 100, 1000, &e);
    ASSERT_TRUE(e.has_value());
    EXPECT_EQ(e->status, 413);
}

}  // namespace
}  // namespace strata::server

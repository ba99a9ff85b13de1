// One connection's reader, without sockets: which requests reach a worker, in what form, and
// which are answered (or refused) before any worker is involved.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "server/request_reader.h"

namespace strata::server {
namespace {

/// A reader's situation: draining, or over a connection limit.
ReaderSituation situation(bool draining, bool restricted) {
    ReaderSituation s;
    s.draining = draining;
    s.restricted = restricted;
    return s;
}

using Kind = ReaderStep::Kind;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

struct Reader {
    explicit Reader(ReaderConfig c = {}) : config(std::move(c)), reader(config) {}
    ReaderStep feed(const std::string& bytes, ReaderSituation s = {}) {
        reader.append(bytes.data(), bytes.size());
        return reader.next(s);
    }
    ReaderConfig config;
    RequestReader reader;
};

TEST(RequestReader, PipelinedRequestsComeOutOneByOneInOrder) {
    Reader r;
    const ReaderStep first = r.feed(
        "POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: 2\r\n\r\n{}"
        "GET /v1/scene HTTP/1.1\r\nHost: a\r\n\r\n");
    ASSERT_EQ(first.kind, Kind::Request);
    EXPECT_EQ(first.request.http.method, "POST");
    EXPECT_EQ(first.request.http.body, "{}");
    EXPECT_TRUE(r.reader.mid_request());
    const ReaderStep second = r.reader.next({});
    ASSERT_EQ(second.kind, Kind::Request);
    EXPECT_EQ(second.request.http.path, "/v1/scene");
    EXPECT_TRUE(second.request.http.body.empty());
    EXPECT_EQ(r.reader.next({}).kind, Kind::NeedMore);
    EXPECT_FALSE(r.reader.mid_request());
}

TEST(RequestReader, ABodyTricklingInIsCollectedBeforeAWorkerSeesIt) {
    Reader r;
    EXPECT_EQ(
        r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: chunked\r\n\r\n3\r\n{\"e")
            .kind,
        Kind::NeedMore);
    EXPECT_TRUE(r.reader.reading_body());
    EXPECT_EQ(r.feed("\r\n").kind, Kind::NeedMore);
    const ReaderStep done = r.feed("1\r\n}\r\n0\r\n\r\n");
    ASSERT_EQ(done.kind, Kind::Request);
    EXPECT_EQ(done.request.http.body, "{\"e}");
}

TEST(RequestReader, HeadersAndQueryReachTheWorkerAsSent) {
    Reader r;
    const ReaderStep s = r.feed(
        "GET /v1/render?width=8&eye=1%2C2%2C3&odd=a%3Db%26c%2Bd%20%25 HTTP/1.1\r\nHost: a\r\n"
        "If-Match: \"%41\"\r\nconnection: keep-alive\r\n\r\n");
    ASSERT_EQ(s.kind, Kind::Request);
    const HttpRequest& http = s.request.http;
    EXPECT_EQ(http.path, "/v1/render");
    // Header values are not decoded: "%41" stays "%41". Names match case-insensitively.
    EXPECT_EQ(http.header_value("if-match"), "\"%41\"");
    EXPECT_EQ(http.header_value("Connection"), "keep-alive");
    EXPECT_EQ(http.header_value("Range"), std::nullopt);
    const std::multimap<std::string, std::string> query = {
        {"width", "8"}, {"eye", "1,2,3"}, {"odd", "a=b&c+d %"}};
    EXPECT_EQ(http.query, query);
    EXPECT_TRUE(s.request.heavy);
}

TEST(RequestReader, OtherMethodsOnHealthPathsAre405WithAllow) {
    Reader r;
    const ReaderStep s = r.feed("POST /livez HTTP/1.1\r\nHost: a\r\nContent-Length: 0\r\n\r\n");
    ASSERT_EQ(s.kind, Kind::Answer);
    EXPECT_EQ(s.answer.status, 405);
    EXPECT_THAT(s.answer.bytes, HasSubstr("Allow: GET, HEAD\r\n"));
}

TEST(RequestReader, HealthChecksAreAnsweredHereEvenWhenDrainingOrRestricted) {
    Reader r;
    ReaderStep live = r.feed("GET /livez HTTP/1.1\r\nHost: a\r\n\r\n", situation(true, true));
    ASSERT_EQ(live.kind, Kind::Answer);
    EXPECT_EQ(live.answer.status, 200);
    ReaderStep ready = r.feed("GET /readyz HTTP/1.1\r\nHost: a\r\n\r\n", situation(true, false));
    ASSERT_EQ(ready.kind, Kind::Answer);
    EXPECT_EQ(ready.answer.status, 503);
    EXPECT_FALSE(ready.answer.close);
    ReaderStep head = r.feed("HEAD /readyz HTTP/1.1\r\nHost: a\r\n\r\n");
    // The GET body's length: {"status":"ready"} and its newline.
    EXPECT_THAT(head.answer.bytes, HasSubstr("Content-Length: 19\r\n"));
    EXPECT_THAT(head.answer.bytes, Not(HasSubstr("ready")));
}

TEST(RequestReader, ReadyzAsksTheReadinessHookAndReportsItsNumbers) {
    Reader r;
    std::function<Readiness()> behind = [] {
        Readiness x;
        x.ready = false;
        x.detail = "the replica stopped following the edit log: poisoned log entry 4-0";
        return x;
    };
    ReaderSituation s;
    s.readiness = &behind;
    ReaderStep stopped = r.feed("GET /readyz HTTP/1.1\r\nHost: a\r\n\r\n", s);
    ASSERT_EQ(stopped.kind, Kind::Answer);
    EXPECT_EQ(stopped.answer.status, 503);
    EXPECT_THAT(stopped.answer.bytes, HasSubstr("poisoned log entry 4-0"));
    // /livez does not ask.
    EXPECT_EQ(r.feed("GET /livez HTTP/1.1\r\nHost: a\r\n\r\n", s).answer.status, 200);

    std::function<Readiness()> following = [] {
        Readiness x;
        x.section = "replica";
        x.numbers = {{"applied_version", 12.0}, {"lag_seconds", 0.25}};
        return x;
    };
    s.readiness = &following;
    ReaderStep ready = r.feed("GET /readyz HTTP/1.1\r\nHost: a\r\n\r\n", s);
    EXPECT_EQ(ready.answer.status, 200);
    EXPECT_THAT(ready.answer.bytes,
                HasSubstr("\"replica\":{\"applied_version\":12,\"lag_seconds\":0.25}"));
    EXPECT_THAT(ready.answer.bytes, HasSubstr("\"status\":\"ready\""));
}

TEST(RequestReader, WhileStartingReadyzSaysHowFarAndEverythingButLivezIsRefusedWithRetryAfter) {
    Reader r;
    const ReaderSituation starting{false, false, true, "replaying the journal, at version 7"};
    ReaderStep ready = r.feed("GET /readyz HTTP/1.1\r\nHost: a\r\n\r\n", starting);
    ASSERT_EQ(ready.kind, Kind::Answer);
    EXPECT_EQ(ready.answer.status, 503);
    EXPECT_THAT(ready.answer.bytes, HasSubstr("starting: replaying the journal, at version 7"));
    EXPECT_THAT(ready.answer.bytes, HasSubstr("Retry-After: 1\r\n"));
    ReaderStep live = r.feed("GET /livez HTTP/1.1\r\nHost: a\r\n\r\n", starting);
    EXPECT_EQ(live.answer.status, 200);
    ReaderStep scene = r.feed("GET /v1/scene HTTP/1.1\r\nHost: a\r\n\r\n", starting);
    ASSERT_EQ(scene.kind, Kind::Answer);
    EXPECT_EQ(scene.answer.status, 503);
    EXPECT_FALSE(scene.answer.close);
    EXPECT_THAT(scene.answer.bytes, HasSubstr("Retry-After: 1\r\n"));
    EXPECT_THAT(scene.answer.bytes, HasSubstr("replaying the journal"));
    // A body is left unread: that connection closes.
    ReaderStep edit =
        r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: 2\r\n\r\n", starting);
    EXPECT_EQ(edit.answer.status, 503);
    EXPECT_TRUE(edit.answer.close);
}

TEST(RequestReader, RefusalsComeBeforeTheBodyIsRead) {
    ReaderConfig c;
    c.token = "t0ken";
    c.limits.max_body_bytes = 100;
    {
        Reader r(c);
        const ReaderStep s =
            r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\nContent-Length: 5\r\n\r\n");
        EXPECT_EQ(s.answer.status, 401);
        EXPECT_TRUE(s.answer.close);
        EXPECT_THAT(s.answer.bytes, HasSubstr("WWW-Authenticate: Bearer"));
    }
    const std::string auth = "Authorization: Bearer t0ken\r\n";
    {
        // Over the cap with Expect: 100-continue: 413 and no 100 first.
        Reader r(c);
        const ReaderStep s = r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\n" + auth +
                                    "Content-Length: 101\r\nExpect: 100-continue\r\n\r\n");
        EXPECT_EQ(s.kind, Kind::Answer);
        EXPECT_EQ(s.answer.status, 413);
    }
    {
        Reader r(c);
        EXPECT_EQ(r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\n" + auth +
                         "Content-Length: 2\r\nExpect: 100-continue\r\n\r\n")
                      .kind,
                  Kind::Continue);
        EXPECT_EQ(r.feed("{}").kind, Kind::Request);
    }
    {
        Reader r(c);
        EXPECT_EQ(r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\n" + auth +
                         "Content-Encoding: gzip\r\nContent-Length: 2\r\n\r\n{}")
                      .answer.status,
                  415);
    }
    {
        Reader r(c);
        const ReaderStep s =
            r.feed("POST /v1/edits HTTP/1.1\r\nHost: a\r\n" + auth +
                   "Transfer-Encoding: chunked\r\n\r\n65\r\n" + std::string(101, 'x'));
        EXPECT_EQ(s.answer.status, 413);
    }
    {
        Reader r(c);
        EXPECT_EQ(
            r.feed("GET /v1/scene HTTP/1.1\r\nHost: a\r\n" + auth + "\r\n", situation(true, false))
                .answer.status,
            503);
        Reader restricted(c);
        EXPECT_EQ(restricted
                      .feed("GET /v1/scene HTTP/1.1\r\nHost: a\r\n" + auth + "\r\n",
                            situation(false, true))
                      .answer.status,
                  429);
    }
}

TEST(RequestReader, AnOversizedHeadIsRefusedWithoutWaitingForItsEnd) {
    ReaderConfig c;
    c.limits.max_head_bytes = 1024;
    Reader r(c);
    ReaderStep s = r.feed("GET / HTTP/1.1\r\nHost: a\r\n");
    for (int i = 0; i < 100 && s.kind == Kind::NeedMore; ++i)
        s = r.feed("X-Filler: 0123456789\r\n");
    EXPECT_EQ(s.kind, Kind::Answer);
    EXPECT_EQ(s.answer.status, 431);
    Reader line(c);
    EXPECT_EQ(line.feed("GET /" + std::string(9000, 'a')).answer.status, 414);
}

TEST(RequestReader, ARefusedHeadRequestGetsNoBody) {
    // Found by the HTTP fuzzer: a body after a HEAD answer is read as the next response.
    Reader r;
    const ReaderStep s = r.feed("HEAD /%zz HTTP/1.1\r\nHost: a\r\n\r\n");
    ASSERT_EQ(s.kind, Kind::Answer);
    EXPECT_EQ(s.answer.status, 400);
    EXPECT_THAT(s.answer.bytes, ::testing::EndsWith("\r\n\r\n"));
    EXPECT_THAT(s.answer.bytes, Not(HasSubstr("percent-escape")));
}

TEST(RequestReader, EveryAnswerIsAProblemDocumentWithItsStatusLine) {
    Reader r;
    const ReaderStep s = r.feed("GET /%zz HTTP/1.1\r\nHost: a\r\n\r\n");
    ASSERT_EQ(s.kind, Kind::Answer);
    EXPECT_THAT(s.answer.bytes, StartsWith("HTTP/1.1 400 Bad Request\r\n"));
    EXPECT_THAT(s.answer.bytes, HasSubstr("Content-Type: application/problem+json\r\n"));
    EXPECT_THAT(s.answer.bytes, HasSubstr("Connection: close\r\n"));
    EXPECT_THAT(s.answer.bytes, HasSubstr("percent-escape"));
}

}  // namespace
}  // namespace strata::server

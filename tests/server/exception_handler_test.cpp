// The exception handler: an exception escaping a handler becomes a 500 problem, and the server
// keeps serving.

#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>

#include "protocol/json_document.h"
#include "server/http_util.h"

namespace strata::server {
namespace {

void expect_internal_problem(const httplib::Response& res) {
    EXPECT_EQ(res.status, 500);
    EXPECT_EQ(res.get_header_value("Content-Type"), "application/problem+json");
    const auto body = protocol::Json::parse(res.body);
    EXPECT_EQ(body["status"], 500);
    EXPECT_EQ(body["detail"], "internal error while handling the request");
    EXPECT_EQ(res.body.find("secret"), std::string::npos) << "internals must not leak";
}

TEST(ExceptionHandler, AnswersA500ProblemForAnyException) {
    httplib::Request req;
    req.method = "GET";
    req.path = "/v1/scene";
    httplib::Response from_std, from_other;
    answer_unhandled_exception(req, from_std,
                               std::make_exception_ptr(std::runtime_error("secret state")));
    answer_unhandled_exception(req, from_other, std::make_exception_ptr(42));
    expect_internal_problem(from_std);
    expect_internal_problem(from_other);
}

TEST(ExceptionHandler, AThrowingRouteGetsA500AndTheServerKeepsServing) {
    httplib::Server http;
    http.set_exception_handler(answer_unhandled_exception);
    http.Get("/throw", [](const httplib::Request&, httplib::Response&) {
        throw std::logic_error("secret bug");
    });
    http.Get("/ok", [](const httplib::Request&, httplib::Response& res) {
        res.set_content("fine", "text/plain");
    });
    const int port = http.bind_to_any_port("127.0.0.1");
    ASSERT_GT(port, 0);
    std::thread serving([&] { http.listen_after_bind(); });
    httplib::Client client("127.0.0.1", port);
    for (int i = 0; i < 3; ++i) {
        const auto r = client.Get("/throw");
        ASSERT_TRUE(r);
        expect_internal_problem(*r);
    }
    const auto ok = client.Get("/ok");
    ASSERT_TRUE(ok);
    EXPECT_EQ(ok->status, 200);
    http.stop();
    serving.join();
}

}  // namespace
}  // namespace strata::server

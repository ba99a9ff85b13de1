#include "server/http_util.h"

#include <spdlog/spdlog.h>

namespace strata::server {

void send_json(httplib::Response& res, int status, const protocol::Json& body) {
    send(res, protocol::json_response(status, body));
}

void send_problem(httplib::Response& res, const protocol::Problem& problem) {
    send(res, protocol::problem_response(problem));
}

void send(httplib::Response& res, protocol::ApiResponse&& answer) {
    res.status = answer.status;
    for (const auto& [name, value] : answer.headers) res.set_header(name, value);
    // What Response::set_content does, without copying the body.
    res.body = std::move(answer.body);
    res.set_header("Content-Type", answer.content_type);
}

void answer_unhandled_exception(const httplib::Request& req, httplib::Response& res,
                                std::exception_ptr error) {
    std::string what = "unknown exception";
    try {
        std::rethrow_exception(error);
    } catch (const std::exception& e) {
        what = e.what();
    } catch (...) {
    }
    spdlog::error("{} {}: unhandled exception: {}", req.method, req.path, what);
    send_problem(res, protocol::make_problem(protocol::ProblemType::Internal,
                                             "internal error while handling the request"));
}

}  // namespace strata::server

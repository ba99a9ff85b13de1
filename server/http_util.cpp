#include "server/http_util.h"

namespace strata::server {

void send_json(httplib::Response& res, int status, const protocol::Json& body) {
    send(res, protocol::json_response(status, body));
}

void send_problem(httplib::Response& res, const protocol::Problem& problem) {
    send(res, protocol::problem_response(problem));
}

void send(httplib::Response& res, const protocol::ApiResponse& answer) {
    res.status = answer.status;
    for (const auto& [name, value] : answer.headers) res.set_header(name, value);
    res.set_content(answer.body, answer.content_type);
}

}  // namespace strata::server

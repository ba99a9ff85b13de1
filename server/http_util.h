#pragma once
// Small helpers shared by the route files: JSON, problem and API responses.

#include <exception>

#include <httplib.h>

#include "protocol/api.h"
#include "protocol/problem.h"

namespace strata::server {

/// Sends `body` as application/json.
void send_json(httplib::Response& res, int status, const protocol::Json& body);
/// Sends an application/problem+json document with the problem's status.
void send_problem(httplib::Response& res, const protocol::Problem& problem);
/// Sends an API answer: its status, headers, body and content type. The body moves into the
/// response uncopied (a frame's encoded bytes go from the encoder to the socket this way).
void send(httplib::Response& res, protocol::ApiResponse&& answer);
/// The server's exception handler: logs what escaped a handler and answers a 500 problem
/// (without internals) instead of letting the exception take the process down.
void answer_unhandled_exception(const httplib::Request& req, httplib::Response& res,
                                std::exception_ptr error);

}  // namespace strata::server

#pragma once
// The one place HTTP responses become bytes: every answer the server sends, from a worker's
// route or from the front end itself (refusals, health checks), and the heads of streams.

#include <string>
#include <string_view>

#include "protocol/api.h"
#include "protocol/problem.h"

namespace strata::server {

/// How a response is framed on its connection.
struct Framing {
    bool close = false;      ///< say `Connection: close` (the connection closes after it)
    bool head_only = false;  ///< a HEAD request: the headers of the body, without it
    /// Not empty: the request's origin, allowed by --cors-origin; its access-control headers
    /// are added (cors.h).
    std::string_view cors_origin;
};

/// The reason phrase of a status ("Not Found").
const char* status_reason(int status);

/// A complete HTTP/1.1 response: status line, Content-Type, Content-Length, Connection, the
/// access-control headers, the answer's own headers, then the body.
std::string write_response(const protocol::ApiResponse& answer, const Framing& framing);

/// The head of a streamed response, which ends with the connection: status line, Content-Type,
/// `Connection: close`, the access-control headers and the answer's own headers, then its body
/// (the bytes before the first part). No Content-Length.
std::string write_stream_head(const protocol::ApiResponse& head, std::string_view cors_origin);

/// A problem document as a complete response.
std::string problem_bytes(const protocol::Problem& problem, bool close);

}  // namespace strata::server

#pragma once
// Responses the front end writes itself, without a worker: refusals (400, 401, 408, 413, ...) and
// the health endpoints. Plain bytes, ready for the socket.

#include <string>

#include "protocol/api.h"
#include "protocol/problem.h"

namespace strata::server {

/// The reason phrase of a status ("Not Found").
const char* status_reason(int status);

/// A complete HTTP/1.1 response: status line, Content-Type, Content-Length, `Connection: close`
/// when `close`, the answer's own headers, then the body unless `head_only` (a HEAD request).
std::string response_bytes(const protocol::ApiResponse& answer, bool close, bool head_only = false);

/// The same for a problem document.
std::string problem_bytes(const protocol::Problem& problem, bool close);

}  // namespace strata::server

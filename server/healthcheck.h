#pragma once
// strata-server --healthcheck: asks a running server whether it is ready, for container
// HEALTHCHECKs and init systems, so that an image needs no HTTP client of its own.

#include <chrono>
#include <string>

namespace strata::server {

/// The address a client should use to reach a server listening on `listen_host`: the wildcard
/// addresses 0.0.0.0 and :: (and an empty host) become the matching loopback address.
std::string healthcheck_target(const std::string& listen_host);

/// GET /readyz on host:port (a wildcard host means this machine). Returns 0 when the answer is
/// 200 and 1 otherwise (no answer within `timeout`, or any other status); prints one line saying
/// which. Never throws.
int run_healthcheck(const std::string& host, int port,
                    std::chrono::milliseconds timeout = std::chrono::seconds(2));

}  // namespace strata::server

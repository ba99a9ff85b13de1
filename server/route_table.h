#pragma once
// httplib as the router and response writer, without its socket handling.
//
// Why: cpp-httplib 0.11 ties a worker thread to each connection for as long as the client takes
// (its read timeout restarts with every byte), parses requests leniently, and applies Range and
// Content-Encoding itself. Strata's front end (reactor.h) owns every socket instead: it reads and
// checks a whole request under a total deadline without a worker, then hands the canonical bytes
// to a RouteTable, which runs httplib's own request processing (routing, handlers, error and
// exception handlers, response formatting, logger) over an in-memory stream. Route handlers keep
// the plain httplib::Request/Response interface.

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include <httplib.h>

#include "engine/core/cancel.h"

namespace strata::server {

class StreamChannel;

/// The two ends of a connection.
struct Peer {
    std::string ip;
    int port = 0;
    std::string local_ip;
    int local_port = 0;
};

/// Per-request state a handler can reach on its worker thread (httplib's Request has no slot).
struct RequestContext {
    /// Cancelled when the client disconnects or the server shuts down; renders poll it (and
    /// set their deadline on it).
    CancelToken* cancel = nullptr;
    /// When the front end had the whole request (queueing time counts in the access log).
    std::chrono::steady_clock::time_point received = std::chrono::steady_clock::now();
    /// Set by the logger when the response says `Connection: close`.
    bool close = false;
    /// Set by a streaming route (stream_routes.cpp): the front end writes this channel instead
    /// of the handler's response.
    std::shared_ptr<StreamChannel> stream;
};

/// The context of the request this thread is handling, or nullptr outside one.
RequestContext* current_request();

class RouteTable : public httplib::Server {
public:
    /// Runs one request (PreparedRequest::wire_bytes) through the routes and returns the whole
    /// response. `close`: the response says `Connection: close`. An exception that escapes
    /// httplib's own handling becomes a 500 problem; nothing propagates.
    std::string handle(std::string_view wire_bytes, const Peer& peer, bool close,
                       RequestContext& context);
};

}  // namespace strata::server

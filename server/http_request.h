#pragma once
// A request as the front end hands it to a worker: read in full and checked (request_reader.h),
// its target normalised and its query decoded (request_target.h).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/http_parser.h"

namespace strata {
class CancelToken;
}

namespace strata::server {

struct Grants;

struct HttpRequest {
    std::string method;
    /// Percent-encoded path: unreserved characters decoded, other escapes as upper-case %XX.
    std::string path;
    /// Decoded query parameters: valid UTF-8, no control characters, names unique.
    std::multimap<std::string, std::string> query;
    /// Every field as sent, framing fields included (the reader has applied them).
    std::vector<HeaderField> headers;
    std::string body;  ///< decoded (chunked framing removed)

    /// The value of the first field named `name` (case-insensitive), or nullptr.
    const std::string* header(std::string_view name) const;
    /// The same as an optional copy.
    std::optional<std::string> header_value(std::string_view name) const;
    /// What `min_version` (query, first) or X-Strata-Min-Version (header) asks for.
    struct MinVersion {
        std::string text;     ///< as sent
        bool valid = false;   ///< a whole number
        uint64_t version = 0;  ///< when valid
    };
    /// Nullopt when the request asks for no version.
    std::optional<MinVersion> min_version() const;
    /// Bytes held by this request (what the front end counts against --max-buffered-mb).
    std::size_t held_bytes() const;
};

/// What the front end tells a handler about the request beyond its bytes.
struct RequestContext {
    /// Cancelled when the client disconnects or the server shuts down; renders poll it (and
    /// set their deadline on it). Null outside the front end (tests, the fuzzer).
    CancelToken* cancel = nullptr;
    /// With --tokens-file: the roles of the request's token (auth.h); null: it may do anything.
    const Grants* grants = nullptr;
};

}  // namespace strata::server

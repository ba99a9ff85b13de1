#pragma once
// A strict HTTP/1.1 request reader (RFC 9112) for the front end. It decides where a request ends
// before any route sees it, so it refuses everything two parsers could read differently (the
// request-smuggling class): conflicting or malformed Content-Length, Content-Length together with
// Transfer-Encoding, transfer codings other than chunked, obs-fold, header lines without a colon,
// whitespace before the colon, bare CR, NUL and other control characters. Pure functions over
// bytes: no sockets, so the fuzzer and the unit tests drive it directly.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "protocol/problem.h"

namespace strata::server {

/// Size limits on one request (ServerConfig holds the flags that set them).
struct HttpLimits {
    std::size_t max_head_bytes = 32 * 1024;  ///< request line and headers together (431)
    std::size_t max_headers = 100;           ///< header fields (431)
    std::size_t max_target_bytes = 8000;     ///< request target (414)
    uint64_t max_body_bytes = 256ull << 20;  ///< decoded body (413)
};

/// Longest header line accepted (431 beyond), as common proxies in front (nginx's 8 KiB header
/// buffers) would.
constexpr std::size_t MAX_HEADER_LINE_BYTES = 8192;

/// One header field as sent (the name keeps its spelling; the value is trimmed of OWS).
struct HeaderField {
    std::string name;
    std::string value;
};

/// The value of the first field in `headers` named `name` (case-insensitive), or nullptr.
const std::string* find_header(const std::vector<HeaderField>& headers, std::string_view name);

/// How the body is delimited.
enum class BodyFraming : uint8_t { None, Length, Chunked };

/// A request line and header block that passed every check.
struct RequestHead {
    std::string method;
    std::string target;     ///< as sent
    int minor_version = 1;  ///< HTTP/1.<minor_version>
    std::vector<HeaderField> headers;
    BodyFraming framing = BodyFraming::None;
    uint64_t content_length = 0;  ///< with BodyFraming::Length
    bool keep_alive = true;       ///< from the version and the Connection header
    bool expect_continue = false;

    const std::string* header(std::string_view name) const { return find_header(headers, name); }
};

/// Case-insensitive ASCII comparison.
bool iequals(std::string_view a, std::string_view b);

/// The offset just past the empty line that ends the head in `buffer`, or npos while it has not
/// arrived. Empty lines before the request line are skipped (RFC 9112 section 2.2). `from` is
/// where the previous call stopped looking (pass the previous buffer size), so that a head that
/// trickles in byte by byte is scanned once, not once per byte.
std::size_t find_head_end(std::string_view buffer, std::size_t from = 0);

/// Parses a complete head (what find_head_end delimits).
std::variant<RequestHead, protocol::Problem> parse_request_head(std::string_view head,
                                                                const HttpLimits& limits);

/// Decodes a chunked body incrementally (RFC 9112 section 7.1): chunk extensions are skipped,
/// trailer fields are read with the header rules and dropped.
class ChunkedDecoder {
public:
    explicit ChunkedDecoder(uint64_t max_body_bytes) : m_max_body(max_body_bytes) {}

    /// Consumes bytes from the front of `in`, appending decoded data to `body`; returns how many
    /// bytes it consumed. Stops at the end of the body (done()) or at an error (error()).
    std::size_t feed(std::string_view in, std::string& body);

    bool done() const { return m_state == State::Done; }
    /// Set once the body is malformed (400) or larger than the limit (413).
    const protocol::Problem* error() const { return m_state == State::Failed ? &m_error : nullptr; }

private:
    enum class State : uint8_t { Size, Data, DataEnd, Trailer, Done, Failed };
    std::size_t fail(protocol::ProblemType type, std::string detail);

    uint64_t m_max_body;
    State m_state = State::Size;
    std::string m_line;        ///< the size or trailer line being assembled
    uint64_t m_remaining = 0;  ///< bytes left in the current chunk
    uint64_t m_decoded = 0;
    std::size_t m_trailer_bytes = 0;
    protocol::Problem m_error;
};

}  // namespace strata::server

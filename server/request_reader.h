#pragma once
// One connection's request reader: bytes from the socket in; out, one step at a time, either a
// complete request checked and ready for a worker, or an answer the front end writes itself
// (a refusal, or /livez and /readyz). Everything that needs no engine happens here, before a
// worker is involved: HTTP parsing, authentication, body limits, Expect: 100-continue, Content-
// Encoding, and the health endpoints. No sockets, so tests and the fuzzer drive it directly.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "protocol/api.h"
#include "server/auth.h"
#include "server/cors.h"
#include "server/http_parser.h"
#include "server/http_request.h"
#include "server/request_target.h"

namespace strata::server {

/// The rules a reader applies beyond the HTTP grammar.
struct ReaderConfig {
    HttpLimits limits;
    std::string token;  ///< bearer token every path but /livez and /readyz needs; empty: none
    /// --tokens-file: tokens with roles per scene (then `token` is empty); null: none.
    std::shared_ptr<const TokenTable> tokens;
    CorsPolicy cors;    ///< origins answered cross-origin (--cors-origin)
};

/// Beyond starting and draining, what /readyz says (a replica following its edit log).
struct Readiness {
    bool ready = true;
    std::string detail;   ///< when not ready: why (the 503 problem's detail)
    std::string section;  ///< when not empty: `numbers` go into the body under this member
    std::vector<std::pair<std::string, double>> numbers;
};

/// What the front end knows when the reader decides.
struct ReaderSituation {
    bool draining = false;    ///< shutting down: only health checks are answered
    bool restricted = false;  ///< the connection is over a connection limit: health checks only
    /// Recovering the scene or building its acceleration structures: /readyz answers 503 with
    /// `progress`, every other request but /livez 503 with Retry-After.
    bool starting = false;
    std::string progress;  ///< while starting: how far, for the answers' detail
    /// Asked by /readyz only (set before serving, never changed); null: ready when not starting.
    const std::function<Readiness()>* readiness = nullptr;
};

/// A complete request for a worker.
struct PreparedRequest {
    HttpRequest http;
    bool keep_alive = true;
    bool heavy = false;  ///< renders and commits, which may take seconds
    /// The request's Origin when --cors-origin allows it: its answer carries the access-control
    /// headers.
    std::string cors_origin;
    /// With --tokens-file: the roles of the token the request carries (access.h).
    std::shared_ptr<const Grants> grants;
};

/// An answer written without a worker.
struct DirectAnswer {
    int status = 0;
    std::string method = "-";  ///< for the access log; "-" when the request line was unreadable
    std::string path = "-";
    std::string bytes;  ///< the whole response
    bool close = true;
};

/// What to do next.
struct ReaderStep {
    enum class Kind : uint8_t {
        NeedMore,  ///< read more bytes
        Continue,  ///< write "100 Continue", then call next() again
        Request,   ///< hand `request` to a worker; call next() again after its answer
        Answer,    ///< write `answer` (then close when it says so)
    };
    Kind kind = Kind::NeedMore;
    PreparedRequest request;
    DirectAnswer answer;
};

/// The paths the front end answers itself, open without a token.
bool is_health_path(std::string_view path);

/// The viewer's static files (GET / and /web/...): no scene data, open without a token (the
/// page asks for the token and sends it with every request it makes).
bool is_public_path(std::string_view path);

/// GET paths that also take the token as the query parameter `access_token`, for browsers'
/// <img> and EventSource, which cannot send an Authorization header. The parameter is removed
/// before the request reaches a route (and the access log, which never shows queries anyway).
bool accepts_query_token(std::string_view path);

/// The query parameter that carries the token on those paths.
inline constexpr const char* QUERY_TOKEN = "access_token";

class RequestReader {
public:
    explicit RequestReader(const ReaderConfig& config) : m_config(config) {}

    /// Appends bytes read from the socket.
    void append(const char* data, std::size_t n) { m_in.append(data, n); }

    /// Advances over the buffered bytes. After an Answer that closes, call it no more.
    ReaderStep next(const ReaderSituation& situation);

    /// True while part of a request has arrived (then a timeout is answered with 408).
    bool mid_request() const { return m_phase == Phase::Body || m_in.size() > m_pos; }
    /// True while the head has arrived and the body is being read.
    bool reading_body() const { return m_phase == Phase::Body; }
    /// Request bytes held in memory (buffered input and the body read so far).
    std::size_t buffered_bytes() const { return m_in.size() + m_body.size(); }
    /// Frees every buffer (the connection is closing; nothing more will be read).
    void discard();

private:
    enum class Phase : uint8_t { Head, Body };

    ReaderStep on_head(const ReaderSituation& situation);
    /// Takes a complete head from the buffer: nullopt when it is well-formed, else what to do
    /// (read more, or the refusal of a malformed head).
    std::optional<ReaderStep> parse_head();
    /// The refusal of a well-formed head that no worker may see, if any.
    std::optional<ReaderStep> refuse(const ReaderSituation& situation);
    ReaderStep on_body();
    ReaderStep answer(protocol::ProblemType type, const std::string& detail, bool close = true,
                      const char* retry_after = nullptr);
    /// Refuses the request with `problem` (its status), closing the connection unless not
    /// `close`.
    ReaderStep refusal(const protocol::Problem& problem, bool close = true,
                       const char* retry_after = nullptr);
    /// Writes `response` to this request (HEAD: without its body; with the access-control
    /// headers of an allowed origin).
    ReaderStep answer_with(const protocol::ApiResponse& response, bool close);
    /// GET /livez or /readyz.
    protocol::ApiResponse health_answer(const ReaderSituation& situation) const;
    ReaderStep finish_request();
    ReaderStep preflight();
    bool authorized();
    const std::optional<std::string>& cors_origin();
    void compact();

    const ReaderConfig& m_config;
    Phase m_phase = Phase::Head;
    std::string m_in;           ///< bytes read and not consumed yet, from m_pos on
    std::size_t m_pos = 0;      ///< start of the unconsumed bytes in m_in
    std::size_t m_scanned = 0;  ///< how far find_head_end has looked
    RequestHead m_head;
    RequestTarget m_target;
    std::string m_body;
    uint64_t m_body_left = 0;  ///< with BodyFraming::Length
    ChunkedDecoder m_chunked{0};
    std::optional<std::string> m_cors_origin;  ///< cors_origin()'s answer for this head
    bool m_cors_checked = false;
    std::shared_ptr<const Grants> m_grants;  ///< authorized()'s match in the tokens file
};

}  // namespace strata::server

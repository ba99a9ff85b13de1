#include "server/request_reader.h"

#include <algorithm>

#include "protocol/api.h"
#include "server/auth.h"
#include "server/response_writer.h"
#include "server/route_table.h"
#include "server/scene_path.h"

namespace strata::server {

namespace {

using protocol::ProblemType;

/// The detail of a 503 while the server starts: what it is doing, and how far it got.
std::string starting_detail(const std::string& progress) {
    return "the server is starting: " +
           (progress.empty() ? std::string("the recovered scene's acceleration structures are "
                                           "being built")
                             : progress);
}

}  // namespace

bool is_health_path(std::string_view path) {
    return path == "/livez" || path == "/readyz";
}

bool is_public_path(std::string_view path) {
    return path == "/" || (path.rfind("/web/", 0) == 0 && path.size() > 5);
}

bool accepts_query_token(std::string_view path) {
    const std::string route = route_of(path);
    return route == "/v1/stream" || route == "/v1/events" || route == "/v1/render";
}

const std::optional<std::string>& RequestReader::cors_origin() {
    if (!m_cors_checked) {
        m_cors_checked = true;
        m_cors_origin = m_config.cors.allow(m_head.header("Origin"));
    }
    return m_cors_origin;
}

bool RequestReader::authorized() {
    m_grants.reset();
    if ((m_config.token.empty() && !m_config.tokens) || is_health_path(m_target.path)) return true;
    const bool get = m_head.method == "GET" || m_head.method == "HEAD";
    if (get && is_public_path(m_target.path)) return true;
    // With a tokens file, the token's grants go with the request (the application checks them
    // against the scene, access.h).
    const auto matches = [&](std::string_view authorization) {
        if (!m_config.tokens) return bearer_token_matches(authorization, m_config.token);
        m_grants = match_grants(*m_config.tokens, authorization);
        return m_grants != nullptr;
    };
    if (const std::string* auth = m_head.header("Authorization")) return matches(*auth);
    if (!get || !accepts_query_token(m_target.path)) return false;
    for (const auto& [name, value] : m_target.query) {
        if (name == QUERY_TOKEN) return matches("Bearer " + value);
    }
    return false;
}

ReaderStep RequestReader::preflight() {
    // A CORS preflight carries no credentials (Fetch standard), so it is answered before the
    // token check. An origin not allowed gets the same 204 without the Access-Control headers:
    // the browser then refuses the real request.
    protocol::ApiResponse r;
    r.status = 204;
    if (cors_origin()) {
        r.headers = {{"Access-Control-Allow-Methods", CORS_ALLOW_METHODS},
                     {"Access-Control-Allow-Headers", CORS_ALLOW_HEADERS},
                     {"Access-Control-Max-Age", "600"}};
    }
    return answer_with(std::move(r), m_head.framing != BodyFraming::None || !m_head.keep_alive);
}

ReaderStep RequestReader::next(const ReaderSituation& situation) {
    return m_phase == Phase::Head ? on_head(situation) : on_body();
}

ReaderStep RequestReader::answer(ProblemType type, const std::string& detail, bool close,
                                 const char* retry_after) {
    return refusal(protocol::make_problem(type, detail), close, retry_after);
}

ReaderStep RequestReader::refusal(const protocol::Problem& problem, bool close,
                                  const char* retry_after) {
    protocol::ApiResponse r = protocol::problem_response(problem);
    if (problem.type == ProblemType::Unauthorized)
        r.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"strata\"");
    if (retry_after) r.headers.emplace_back("Retry-After", retry_after);
    return answer_with(std::move(r), close);
}

ReaderStep RequestReader::answer_with(const protocol::ApiResponse& response, bool close) {
    ReaderStep step;
    step.kind = ReaderStep::Kind::Answer;
    step.answer.status = response.status;
    step.answer.close = close;
    Framing framing;
    framing.close = close;
    if (!m_head.method.empty()) {
        step.answer.method = m_head.method;
        step.answer.path = m_target.path.empty() ? m_head.target : m_target.path;
        framing.head_only = m_head.method == "HEAD";
        if (const auto& origin = cors_origin()) framing.cors_origin = *origin;
    }
    step.answer.bytes = write_response(response, framing);
    return step;
}

protocol::ApiResponse RequestReader::health_answer(const ReaderSituation& situation) const {
    const bool livez = m_target.path == "/livez";
    Readiness extra;
    if (!livez && situation.readiness && *situation.readiness) extra = (*situation.readiness)();
    const bool ready = livez || (!situation.draining && !situation.starting && extra.ready);
    if (!ready) {
        protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
            ProblemType::Unavailable, situation.draining   ? "the server is shutting down"
                                      : situation.starting ? starting_detail(situation.progress)
                                                           : extra.detail));
        if (!situation.draining) r.headers.emplace_back("Retry-After", "1");
        return r;
    }
    protocol::Json report = {{"status", livez ? "ok" : "ready"}};
    if (!livez && !extra.section.empty()) {
        protocol::Json& section = report[extra.section];
        for (const auto& [name, value] : extra.numbers) {
            // Versions and counts are whole numbers: written as integers.
            if (value >= 0 && value < 9007199254740992.0 && value == double(int64_t(value)))
                section[name] = int64_t(value);
            else
                section[name] = value;
        }
    }
    return protocol::json_response(200, report);
}

std::optional<ReaderStep> RequestReader::parse_head() {
    const HttpLimits& limits = m_config.limits;
    // Empty lines between requests (some clients end a body with an extra CRLF) are no request:
    // dropped here, they neither count as one in progress nor start its deadline.
    while (m_pos < m_in.size()) {
        const std::size_t n = m_in[m_pos] == '\n' ? 1 : m_in.compare(m_pos, 2, "\r\n") == 0 ? 2 : 0;
        if (n == 0) break;
        m_pos += n;
        m_scanned -= std::min(m_scanned, n);
    }
    const std::string_view buffered = std::string_view(m_in).substr(m_pos);
    const std::size_t end = find_head_end(buffered, m_scanned);
    if (end == std::string_view::npos) {
        m_scanned = buffered.size();
        if (buffered.size() <= limits.max_head_bytes) return ReaderStep{};
        if (buffered.find('\n') == std::string_view::npos &&
            buffered.size() > limits.max_target_bytes)
            return answer(ProblemType::UriTooLong, "the request line is longer than the limit of " +
                                                       std::to_string(limits.max_target_bytes) +
                                                       " bytes for its target (--max-uri-bytes)");
        return answer(ProblemType::HeadersTooLarge, "the request head is larger than " +
                                                        std::to_string(limits.max_head_bytes) +
                                                        " bytes (--max-header-bytes)");
    }
    m_scanned = 0;
    m_head = RequestHead{};
    m_target = RequestTarget{};
    m_cors_checked = false;
    m_cors_origin.reset();
    auto parsed = parse_request_head(buffered.substr(0, end), limits);
    m_pos += end;
    if (auto* e = std::get_if<protocol::Problem>(&parsed)) return refusal(*e);
    m_head = std::move(std::get<RequestHead>(parsed));
    auto target = parse_request_target(m_head.target);
    if (auto* e = std::get_if<protocol::Problem>(&target)) return refusal(*e);
    m_target = std::move(std::get<RequestTarget>(target));
    return std::nullopt;
}

std::optional<ReaderStep> RequestReader::refuse(const ReaderSituation& situation) {
    const bool body = m_head.framing != BodyFraming::None;
    // The body is left unread: the connection closes.
    if (situation.draining) return answer(ProblemType::Unavailable, "the server is shutting down");
    if (situation.starting) {
        // Refused without reading a body (a connection with one unread closes); the client
        // comes back when the scene is ready.
        return answer(ProblemType::Unavailable, starting_detail(situation.progress),
                      body || !m_head.keep_alive, "1");
    }
    if (situation.restricted)
        return answer(ProblemType::TooManyConnections,
                      "this client holds too many connections already "
                      "(--max-connections-per-client, --max-connections); only /livez and "
                      "/readyz are answered on this one");
    if (m_head.method == "OPTIONS" && m_head.header("Origin") &&
        m_head.header("Access-Control-Request-Method"))
        return preflight();
    if (!authorized()) {
        const std::string* auth = m_head.header("Authorization");
        return answer(ProblemType::Unauthorized,
                      auth ? "the bearer token is not valid"
                      : accepts_query_token(m_target.path)
                          ? "this server requires Authorization: Bearer <token> (or, "
                            "from a browser, ?access_token=<token>)"
                          : "this server requires Authorization: Bearer <token>");
    }
    if (const std::string* coding = m_head.header("Content-Encoding");
        coding && !iequals(*coding, "identity"))
        return answer(ProblemType::UnsupportedEncoding,
                      "Content-Encoding '" + coding->substr(0, 32) +
                          "' is not accepted: send the body uncompressed");
    const uint64_t max_body = m_config.limits.max_body_bytes;
    if (m_head.framing == BodyFraming::Length && m_head.content_length > max_body)
        return answer(ProblemType::TooLarge,
                      "the request body of " + std::to_string(m_head.content_length) +
                          " bytes is larger than the limit of " + std::to_string(max_body) +
                          " bytes (--max-body-mb)");
    return std::nullopt;
}

ReaderStep RequestReader::on_head(const ReaderSituation& situation) {
    if (std::optional<ReaderStep> early = parse_head()) return std::move(*early);

    // Step: health checks, answered here so that they never wait for a worker, whatever the
    // load, the connection limits or the shutdown state.
    const bool body = m_head.framing != BodyFraming::None;
    if (is_health_path(m_target.path)) {
        if (m_head.method != "GET" && m_head.method != "HEAD")
            return answer_with(method_not_allowed(m_head.method, m_target.path, "GET, HEAD"),
                               body || !m_head.keep_alive);
        return answer_with(health_answer(situation), body || !m_head.keep_alive);
    }

    // Step: refusals that need no body.
    if (std::optional<ReaderStep> refusal = refuse(situation)) return std::move(*refusal);
    // The token in the query is never passed on: routes would refuse an unknown parameter.
    m_target.query.erase(std::remove_if(m_target.query.begin(), m_target.query.end(),
                                        [](const auto& p) { return p.first == QUERY_TOKEN; }),
                         m_target.query.end());
    if (!body) return finish_request();

    // Step: the body, read here in full before a worker sees the request.
    m_phase = Phase::Body;
    m_body.clear();
    m_body_left = m_head.content_length;
    m_chunked = ChunkedDecoder(m_config.limits.max_body_bytes);
    if (m_head.expect_continue && m_pos == m_in.size()) {
        ReaderStep step;
        step.kind = ReaderStep::Kind::Continue;
        return step;
    }
    return on_body();
}

ReaderStep RequestReader::on_body() {
    const std::string_view buffered = std::string_view(m_in).substr(m_pos);
    if (m_head.framing == BodyFraming::Length) {
        const std::size_t n = std::size_t(std::min<uint64_t>(m_body_left, buffered.size()));
        m_body.append(buffered.substr(0, n));
        m_pos += n;
        m_body_left -= n;
        compact();
        if (m_body_left > 0) return {};
    } else {
        m_pos += m_chunked.feed(buffered, m_body);
        compact();
        if (const protocol::Problem* e = m_chunked.error()) return refusal(*e);
        if (!m_chunked.done()) return {};
    }
    return finish_request();
}

ReaderStep RequestReader::finish_request() {
    ReaderStep step;
    step.kind = ReaderStep::Kind::Request;
    PreparedRequest& r = step.request;
    if (const auto& origin = cors_origin()) r.cors_origin = *origin;  // before the headers move
    r.http.method = m_head.method;
    r.http.path = std::move(m_target.path);
    for (auto& [name, value] : m_target.query)
        r.http.query.emplace(std::move(name), std::move(value));
    r.http.headers = std::move(m_head.headers);
    r.http.body = std::move(m_body);
    m_body = std::string();
    r.keep_alive = m_head.keep_alive;
    r.grants = std::move(m_grants);
    const std::string route = route_of(r.http.path);
    r.heavy = route == "/v1/render" || route == "/v1/commit";
    m_phase = Phase::Head;
    compact();
    return step;
}

void RequestReader::discard() {
    m_in = std::string();
    m_body = std::string();
    m_pos = m_scanned = 0;
    m_phase = Phase::Head;
}

void RequestReader::compact() {
    if (m_pos == m_in.size()) {
        m_in.clear();
        m_pos = 0;
        if (m_in.capacity() > (64u << 10)) m_in.shrink_to_fit();
    } else if (m_pos > (64u << 10) && m_pos * 2 > m_in.size()) {
        m_in.erase(0, m_pos);
        m_pos = 0;
    }
}

}  // namespace strata::server

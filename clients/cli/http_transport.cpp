#include "clients/cli/http_transport.h"

#include <cctype>

#include <httplib.h>

namespace strata::cli {

namespace {

std::string describe_error(httplib::Error e) {
    switch (e) {
        case httplib::Error::Connection:
            return "could not connect";
        case httplib::Error::ConnectionTimeout:
            return "timed out connecting";
        case httplib::Error::Read:
            return "the connection failed or timed out while reading the answer";
        case httplib::Error::Write:
            return "the connection failed while sending the request";
        case httplib::Error::SSLConnection:
        case httplib::Error::SSLLoadingCerts:
        case httplib::Error::SSLServerVerification:
            return "TLS failed (" + httplib::to_string(e) + ")";
        default:
            return "request failed (" + httplib::to_string(e) + ")";
    }
}

/// Accepts http://host[:port][/] and https://host[:port][/]; the base URL without the slash.
Outcome<std::string> check_url(const std::string& url) {
    const std::size_t scheme_end = url.find("://");
    const std::string scheme = scheme_end == std::string::npos ? "" : url.substr(0, scheme_end);
    if (scheme != "http" && scheme != "https")
        return Unexpected(Failure{"server URL '" + url + "' must start with http:// or https://"});
    std::string rest = url.substr(scheme_end + 3);
    if (!rest.empty() && rest.back() == '/') rest.pop_back();
    if (rest.empty()) return Unexpected(Failure{"server URL '" + url + "' has no host"});
    if (rest.find_first_of("/?#@") != std::string::npos)
        return Unexpected(
            Failure{"server URL '" + url + "' must be scheme://host[:port], without a path"});
    const std::size_t colon = rest.rfind(':');
    if (colon != std::string::npos && rest.find(']') == std::string::npos) {
        const std::string port = rest.substr(colon + 1);
        bool digits = !port.empty() && port.size() <= 5;
        for (char c : port) digits = digits && std::isdigit(static_cast<unsigned char>(c));
        if (!digits) return Unexpected(Failure{"server URL '" + url + "' has a malformed port"});
    }
    return scheme + "://" + rest;
}

Reply to_reply(const httplib::Result& r, const std::string& url) {
    Reply out;
    if (!r) {
        out.error = describe_error(r.error()) + " (" + url + ")";
        return out;
    }
    out.status = r->status;
    out.body = r->body;
    out.content_type = r->get_header_value("Content-Type");
    for (const auto& [name, value] : r->headers) out.headers.emplace_back(name, value);
    return out;
}

/// `path` with `query` appended, keys and values percent-encoded.
std::string with_query(std::string path, const std::multimap<std::string, std::string>& query) {
    char sep = '?';
    for (const auto& [key, value] : query) {
        path += sep + percent_encode(key) + "=" + percent_encode(value);
        sep = '&';
    }
    return path;
}

}  // namespace

Outcome<std::unique_ptr<HttpTransport>> HttpTransport::create(const HttpOptions& options) {
    auto url = check_url(options.url);
    if (!url) return Unexpected(url.error());
    auto client = std::make_unique<httplib::Client>(url.value());
    if (!client->is_valid())
        return Unexpected(Failure{"cannot use server URL '" + options.url + "'"});
    client->set_keep_alive(true);
    // Headers and body go out in separate writes: without TCP_NODELAY, Nagle's algorithm and the
    // server's delayed ACK add ~40 ms to every request with a body.
    client->set_tcp_nodelay(true);
    client->set_connection_timeout(options.timeout_s, 0);
    client->set_read_timeout(options.timeout_s, 0);
    client->set_write_timeout(options.timeout_s, 0);
    if (!options.token.empty()) client->set_bearer_token_auth(options.token);
    return std::unique_ptr<HttpTransport>(new HttpTransport(
        url.value(), percent_encode(options.scene), std::move(client), options.on_answer));
}

HttpTransport::HttpTransport(std::string url, std::string scene,
                             std::unique_ptr<httplib::Client> client,
                             decltype(HttpOptions::on_answer) on_answer)
    : m_url(std::move(url)),
      m_scene(std::move(scene)),
      m_client(std::move(client)),
      m_on_answer(std::move(on_answer)) {}

HttpTransport::~HttpTransport() = default;

std::string HttpTransport::scoped(const char* path) const {
    const std::string_view p(path);
    if (m_scene.empty() || p.substr(0, 4) != "/v1/" || p.substr(0, 10) == "/v1/scenes")
        return std::string(p);
    return "/v1/scenes/" + m_scene + "/" + std::string(p.substr(4));
}

Reply HttpTransport::get(const char* path) {
    const std::string target = scoped(path);
    Reply reply = to_reply(m_client->Get(target), m_url);
    if (m_on_answer) m_on_answer("GET", target, reply);
    return reply;
}

Reply HttpTransport::post(const char* path, const std::string& body, const std::string& if_match,
                          const char* content_type) {
    httplib::Headers headers;
    if (!if_match.empty()) headers.emplace("If-Match", if_match);
    const std::string target = scoped(path);
    Reply reply = to_reply(m_client->Post(target, headers, body, content_type), m_url);
    if (m_on_answer) m_on_answer("POST", target, reply);
    return reply;
}

Reply HttpTransport::put_or_delete(const std::string& path, const std::string* body,
                                   const char* content_type) {
    const std::string target = scoped(path.c_str());
    Reply reply = to_reply(body ? m_client->Put(target, *body, content_type)
                                : m_client->Delete(target),
                           m_url);
    if (m_on_answer) m_on_answer(body ? "PUT" : "DELETE", target, reply);
    return reply;
}

Reply HttpTransport::scenes() {
    return get("/v1/scenes");
}

Reply HttpTransport::put_scene(const std::string& name, const std::string& body) {
    const std::string target = "/v1/scenes/" + percent_encode(name);
    Reply reply = to_reply(m_client->Put(target, body, "application/json"), m_url);
    if (m_on_answer) m_on_answer("PUT", target, reply);
    return reply;
}

Reply HttpTransport::delete_scene(const std::string& name) {
    const std::string target = "/v1/scenes/" + percent_encode(name);
    Reply reply = to_reply(m_client->Delete(target), m_url);
    if (m_on_answer) m_on_answer("DELETE", target, reply);
    return reply;
}

Reply HttpTransport::edits(std::string body, const std::optional<std::string>& if_match) {
    return post("/v1/edits", body, if_match.value_or(""));
}

Reply HttpTransport::undo(bool redo, const std::optional<std::string>& if_match) {
    return post(redo ? "/v1/redo" : "/v1/undo", "", if_match.value_or(""));
}

Reply HttpTransport::history(const std::multimap<std::string, std::string>& query) {
    return get(with_query("/v1/history", query).c_str());
}

Reply HttpTransport::commit() {
    return post("/v1/commit", "", "");
}

Reply HttpTransport::plan() {
    return get("/v1/plan");
}

Reply HttpTransport::render(const std::string& body) {
    return post("/v1/render", body, "");
}

Reply HttpTransport::stats() {
    return get("/v1/stats");
}

Reply HttpTransport::scene() {
    return get("/v1/scene");
}

Reply HttpTransport::scene_list(const std::string& collection,
                                const std::multimap<std::string, std::string>& query) {
    return get(with_query("/v1/scene/" + percent_encode(collection), query).c_str());
}

Reply HttpTransport::scene_object(const std::string& collection, const std::string& id) {
    return get(("/v1/scene/" + percent_encode(collection) + "/" + percent_encode(id)).c_str());
}

Reply HttpTransport::pick(const std::string& body) {
    return post("/v1/pick", body, "");
}

Reply HttpTransport::get_snapshot(std::optional<uint64_t> at_version,
                                  const std::optional<std::string>& at_time) {
    if (at_version)
        return get(("/v1/scene/snapshot?at_version=" + std::to_string(*at_version)).c_str());
    if (at_time) return get(("/v1/scene/snapshot?at_time=" + percent_encode(*at_time)).c_str());
    return get("/v1/scene/snapshot");
}

Reply HttpTransport::put_snapshot(std::string bytes) {
    return post("/v1/scene/snapshot", bytes, "", "application/vnd.strata.snapshot");
}

Reply HttpTransport::import_asset(std::string bytes,
                                  const std::multimap<std::string, std::string>& query) {
    // The format travels in the query (?format= or the name's extension).
    return post(with_query("/v1/assets", query).c_str(), bytes, "", "application/octet-stream");
}

Reply HttpTransport::assets(const std::optional<std::string>& id) {
    return get(id ? ("/v1/assets/" + percent_encode(*id)).c_str() : "/v1/assets");
}

Reply HttpTransport::delete_asset(const std::string& id) {
    return put_or_delete("/v1/assets/" + percent_encode(id), nullptr, "");
}

Reply HttpTransport::put_asset(const std::string& id, std::string bytes,
                               const std::multimap<std::string, std::string>& query) {
    return put_or_delete(with_query("/v1/assets/" + percent_encode(id), query), &bytes,
                         "application/octet-stream");
}

}  // namespace strata::cli

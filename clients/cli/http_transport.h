#pragma once
// The protocol over HTTP with cpp-httplib: one keep-alive connection, bearer token, timeouts.

#include <functional>
#include <memory>
#include <string>

#include "clients/cli/outcome.h"
#include "clients/cli/transport.h"

namespace httplib {
class Client;
}

namespace strata::cli {

/// Connection settings.
struct HttpOptions {
    std::string url = "http://127.0.0.1:7070";  ///< scheme://host[:port], no path
    std::string token;                          ///< bearer token; empty: none
    int timeout_s = 300;                        ///< connect, read and write timeout
    /// Called with each request's method and target and the answer it got (tests record them).
    std::function<void(const char* method, const std::string& target, const Reply& reply)>
        on_answer;
    /// A named scene: every scene request goes to /v1/scenes/{scene}/...; empty: the default.
    std::string scene;
};

class HttpTransport final : public Transport {
public:
    /// Checks the URL; connects lazily, on the first request.
    static Outcome<std::unique_ptr<HttpTransport>> create(const HttpOptions& options);
    ~HttpTransport() override;

    Reply edits(std::string body, const std::optional<std::string>& if_match) override;
    Reply undo(bool redo, const std::optional<std::string>& if_match) override;
    Reply history(const std::multimap<std::string, std::string>& query) override;
    Reply commit() override;
    Reply plan() override;
    Reply render(const std::string& body) override;
    Reply stats() override;
    Reply scene() override;
    Reply scene_list(const std::string& collection,
                     const std::multimap<std::string, std::string>& query) override;
    Reply scene_object(const std::string& collection, const std::string& id) override;
    Reply pick(const std::string& body) override;
    Reply get_snapshot(std::optional<uint64_t> at_version,
                       const std::optional<std::string>& at_time) override;
    Reply put_snapshot(std::string bytes) override;
    Reply import_asset(std::string bytes,
                       const std::multimap<std::string, std::string>& query) override;
    Reply assets(const std::optional<std::string>& id) override;
    Reply delete_asset(const std::string& id) override;
    Reply put_asset(const std::string& id, std::string bytes,
                    const std::multimap<std::string, std::string>& query) override;
    Reply scenes() override;
    Reply put_scene(const std::string& name, const std::string& body) override;
    Reply delete_scene(const std::string& name) override;
    std::string describe() const override { return m_url; }

private:
    HttpTransport(std::string url, std::string scene, std::unique_ptr<httplib::Client> client,
                  decltype(HttpOptions::on_answer) on_answer);
    /// `path` in the transport's scene: /v1/X as /v1/scenes/{scene}/X.
    std::string scoped(const char* path) const;
    Reply get(const char* path);
    Reply post(const char* path, const std::string& body, const std::string& if_match,
               const char* content_type = "application/json");
    /// PUT or DELETE (`body` null) of `path` in the transport's scene.
    Reply put_or_delete(const std::string& path, const std::string* body,
                        const char* content_type);

    std::string m_url;
    std::string m_scene;  ///< percent-encoded; empty: the default scene
    std::unique_ptr<httplib::Client> m_client;
    decltype(HttpOptions::on_answer) m_on_answer;
};

}  // namespace strata::cli

#pragma once
// The real server, in-process on a free loopback port, and a real httplib client.

#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>
#include <spdlog/spdlog.h>

#include "engine/engine.h"
#include "engine/scene/demo_scene.h"
#include "protocol/json_document.h"
#include "server/auth.h"
#include "server/server.h"
#include "tests/server/answer_log.h"

namespace strata::server::test {

using protocol::Json;

/// One HTTP exchange's outcome.
struct Reply {
    int status = 0;  ///< 0: no response (connection error)
    std::string body;
    httplib::Headers headers;

    std::string header(const char* name) const {
        auto it = headers.find(name);
        return it == headers.end() ? std::string() : it->second;
    }
    Json json() const { return Json::parse(body, nullptr, false); }
};

inline Reply to_reply(const httplib::Result& r) {
    if (!r) return {0, "no response: " + httplib::to_string(r.error()), {}};
    return {r->status, r->body, r->headers};
}

class TestServer {
public:
    explicit TestServer(ServerConfig config = {}, bool demo = false,
                        const EngineConfig& engine_config = {}) {
        spdlog::set_level(std::getenv("STRATA_TEST_LOG") ? spdlog::level::info : spdlog::level::warn);
        auto engine = Engine::create(engine_config);
        EXPECT_TRUE(engine.has_value());
        m_engine = std::move(engine.value());
        if (demo) {
            EXPECT_TRUE(m_engine->apply(make_demo_scene()).has_value());
        }
        config.host = "127.0.0.1";
        config.port = 0;
        m_server = std::make_unique<Server>(config, *m_engine);
        auto port = m_server->bind();
        EXPECT_TRUE(port.has_value());
        m_port = port.has_value() ? port.value() : 0;
        m_thread = std::thread([this] { m_server->listen(); });
        if (auto log = AnswerLog::from_environment()) {
            httplib::Headers auth;
            if (!config.token.empty()) auth.emplace("Authorization", "Bearer " + config.token);
            // With a tokens file, any of its tokens may read the description.
            if (config.tokens)
                auth.emplace("Authorization", "Bearer " + config.tokens->entries.front().first);
            log->description(get("/v1/openapi.json", auth).body);  // before the log is on
            m_answers = std::move(log);
        }
    }
    ~TestServer() {
        m_server->stop();
        m_thread.join();
    }

    httplib::Client client() const {
        httplib::Client c("127.0.0.1", m_port);
        c.set_read_timeout(30, 0);
        c.set_write_timeout(30, 0);
        if (m_answers) {
            c.set_logger([log = m_answers](const httplib::Request& q, const httplib::Response& a) {
                log->answer(q.method, q.path, a.status, a.get_header_value("Content-Type"), a.body);
            });
        }
        return c;
    }
    /// Where the answers this server gives go when they are recorded (null: they are not).
    std::shared_ptr<AnswerLog> answers() const { return m_answers; }
    Reply get(const std::string& path, const httplib::Headers& h = {}) const {
        auto c = client();
        return to_reply(c.Get(path.c_str(), h));
    }
    Reply post(const std::string& path, const std::string& body,
               const httplib::Headers& h = {}) const {
        auto c = client();
        return to_reply(c.Post(path.c_str(), h, body, "application/json"));
    }
    /// POST with the body typed `content_type`.
    Reply post_as(const std::string& path, const std::string& body,
                  const std::string& content_type) const {
        auto c = client();
        return to_reply(c.Post(path.c_str(), body, content_type.c_str()));
    }
    Reply post(const std::string& path, const Json& body, const httplib::Headers& h = {}) const {
        return post(path, body.dump(), h);
    }
    /// POST /v1/edits with {"edits": edits}.
    Reply edits(const Json& edits, const httplib::Headers& h = {}) const {
        Json body = Json::object();
        body["edits"] = edits;
        return post("/v1/edits", body, h);
    }
    /// The same with the edits listed in braces (always an array, even of one edit).
    Reply edits(std::initializer_list<Json> list, const httplib::Headers& h = {}) const {
        Json edits = Json::array();
        for (const Json& e : list) edits.push_back(e);
        return this->edits(edits, h);
    }

    Engine& engine() { return *m_engine; }
    Server& server() { return *m_server; }
    int port() const { return m_port; }

private:
    std::unique_ptr<Engine> m_engine;
    std::unique_ptr<Server> m_server;
    std::thread m_thread;
    int m_port = 0;
    std::shared_ptr<AnswerLog> m_answers;
};

/// A one-triangle mesh edit.
inline Json triangle_mesh(const std::string& id) {
    return {{"op", "add_mesh"},
            {"id", id},
            {"positions", {0, 0, 0, 1, 0, 0, 0, 1, 0}},
            {"indices", {0, 1, 2}}};
}

/// Asserts a problem document with `status` and, when given, `type` slug and `pointer`.
inline void expect_problem(const Reply& r, int status, const std::string& slug = {},
                           const std::string& pointer = {}) {
    EXPECT_EQ(r.status, status) << r.body;
    EXPECT_EQ(r.header("Content-Type"), "application/problem+json") << r.body;
    const Json j = r.json();
    EXPECT_EQ(j.value("status", 0), status) << r.body;
    EXPECT_TRUE(j.contains("title")) << r.body;
    EXPECT_FALSE(j.value("detail", std::string()).empty()) << r.body;
    if (!slug.empty()) {
        EXPECT_EQ(j.value("type", std::string()), "https://strata.dev/problems/" + slug) << r.body;
    }
    if (!pointer.empty()) {
        EXPECT_EQ(j.value("pointer", std::string()), pointer) << r.body;
    }
}

}  // namespace strata::server::test

// strata-server --healthcheck: 0 for a server that answers /readyz with 200, 1 for anything else.

#include "server/healthcheck.h"

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>

#include "tests/server/process_util.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

using namespace std::chrono_literals;

/// A bare httplib server on a free loopback port whose /readyz answers `status` after `delay`.
class StubServer {
public:
    StubServer(int status, std::chrono::milliseconds delay) {
        m_http.Get("/readyz", [status, delay](const httplib::Request&, httplib::Response& res) {
            std::this_thread::sleep_for(delay);
            res.status = status;
            res.set_content("{}", "application/json");
        });
        m_port = m_http.bind_to_any_port("127.0.0.1");
        m_thread = std::thread([this] { m_http.listen_after_bind(); });
        // The socket is bound already, so connections queue; stop() needs listen to have begun.
        while (!m_http.is_running()) std::this_thread::sleep_for(1ms);
    }
    ~StubServer() {
        m_http.stop();
        m_thread.join();
    }
    int port() const { return m_port; }

private:
    httplib::Server m_http;
    std::thread m_thread;
    int m_port = 0;
};

TEST(Healthcheck, WildcardListenAddressesMeanThisMachine) {
    EXPECT_EQ(healthcheck_target("0.0.0.0"), "127.0.0.1");
    EXPECT_EQ(healthcheck_target(""), "127.0.0.1");
    EXPECT_EQ(healthcheck_target("::"), "::1");
    EXPECT_EQ(healthcheck_target("127.0.0.5"), "127.0.0.5");
    EXPECT_EQ(healthcheck_target("localhost"), "localhost");
}

TEST(Healthcheck, AReadyServerIsHealthy) {
    TestServer srv;
    EXPECT_EQ(run_healthcheck("127.0.0.1", srv.port()), 0);
    EXPECT_EQ(run_healthcheck("0.0.0.0", srv.port()), 0);
}

TEST(Healthcheck, APortNobodyListensOnIsUnhealthy) {
    EXPECT_EQ(run_healthcheck("127.0.0.1", free_port()), 1);
}

TEST(Healthcheck, AnyStatusButOkIsUnhealthy) {
    StubServer shutting_down(503, 0ms);
    EXPECT_EQ(run_healthcheck("127.0.0.1", shutting_down.port()), 1);
    StubServer ok(200, 0ms);
    EXPECT_EQ(run_healthcheck("127.0.0.1", ok.port()), 0);
}

TEST(Healthcheck, AnAnswerSlowerThanTheTimeoutIsUnhealthy) {
    StubServer slow(200, 1000ms);
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(run_healthcheck("127.0.0.1", slow.port(), 200ms), 1);
    EXPECT_LT(std::chrono::steady_clock::now() - start, 800ms);
}

/// Runs `strata-server --healthcheck` with `args` and `env`; returns its exit status.
int healthcheck_exit(std::vector<std::string> args, const std::vector<std::string>& env = {}) {
    args.insert(args.begin(), "--healthcheck");
    return wait_exit(spawn_server(args, env), 10);
}

TEST(Healthcheck, TheProgramExitsZeroForALiveServerAndOneForADeadPort) {
    TestServer srv;
    const std::string live = std::to_string(srv.port());
    EXPECT_EQ(healthcheck_exit({"--port", live}), 0);
    // The way the image runs it: the listen address and port come from the environment.
    EXPECT_EQ(healthcheck_exit({}, {"STRATA_HOST=0.0.0.0", "STRATA_PORT=" + live}), 0);
    EXPECT_EQ(healthcheck_exit({"--port", std::to_string(free_port())}), 1);
}

TEST(Healthcheck, TheProgramNeedsNoTokenEvenWhenTheServerDoes) {
    ServerConfig config;
    config.token = "s3cret";
    TestServer srv(config);
    EXPECT_EQ(healthcheck_exit({"--port", std::to_string(srv.port())}, {"STRATA_HOST=0.0.0.0"}), 0);
}

}  // namespace
}  // namespace strata::server::test

// The strata-server program itself: SIGTERM and SIGINT finish in-flight requests and exit 0, and
// the command-line refusals exit non-zero.

#include <signal.h>

#include <chrono>
#include <future>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <httplib.h>

#include "tests/server/process_util.h"

namespace strata::server::test {
namespace {

void finishes_in_flight_work_on(int signo) {
    const int port = free_port();
    // A grace long enough for the render below on a loaded machine (past it, renders stop: see
    // tests/server/test_adversarial.py).
    const pid_t pid =
        spawn_server({"--demo", "--port", std::to_string(port), "--shutdown-grace", "120"});
    ASSERT_TRUE(wait_ready(port));
    // A large frame of many samples, so that the signal lands while it renders.
    auto slow = std::async(std::launch::async, [port] {
        httplib::Client c("127.0.0.1", port);
        c.set_read_timeout(120, 0);
        auto r = c.Get("/v1/render?width=1024&height=1024&spp=4");
        return r ? r->status : 0;
    });
    // The signal lands once a worker holds the render: in flight are it and this /metrics.
    bool rendering = false;
    for (int i = 0; i < 1000 && !rendering; ++i) {
        rendering = metric_value(port, "strata_http_requests_in_flight") >= 2;
        if (!rendering) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_TRUE(rendering) << "the render never reached a worker";
    ASSERT_EQ(kill(pid, signo), 0);
    EXPECT_EQ(slow.get(), 200);
    EXPECT_EQ(wait_exit(pid, 60), 0);
    // And it no longer listens.
    httplib::Client c("127.0.0.1", port);
    EXPECT_FALSE(c.Get("/livez"));
}

TEST(Shutdown, SigtermFinishesInFlightRequestsAndExitsZero) {
    finishes_in_flight_work_on(SIGTERM);
}

TEST(Shutdown, SigintFinishesInFlightRequestsAndExitsZero) {
    finishes_in_flight_work_on(SIGINT);
}

TEST(Shutdown, AnIdleServerStopsAtOnce) {
    const int port = free_port();
    const pid_t pid = spawn_server({"--port", std::to_string(port)});
    ASSERT_TRUE(wait_ready(port));
    kill(pid, SIGTERM);
    EXPECT_EQ(wait_exit(pid, 10), 0);
}

TEST(CommandLine, RefusesANonLoopbackHostWithoutAToken) {
    EXPECT_EQ(
        wait_exit(spawn_server({"--host", "0.0.0.0", "--port", std::to_string(free_port())}), 10),
        2);
}

TEST(CommandLine, RefusesUnknownFlagsAndAnswersHelp) {
    EXPECT_NE(wait_exit(spawn_server({"--no-such-flag"}), 10), 0);
    EXPECT_EQ(wait_exit(spawn_server({"--help"}), 10), 0);
}

}  // namespace
}  // namespace strata::server::test

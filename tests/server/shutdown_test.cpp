// The strata-server program itself: SIGTERM and SIGINT finish in-flight requests and exit 0, and
// the command-line refusals exit non-zero.

#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>

extern char** environ;

namespace strata::server::test {
namespace {

int free_port() {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    socklen_t len = sizeof addr;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    ::close(fd);
    return ntohs(addr.sin_port);
}

/// Runs strata-server with `args`; returns its pid.
pid_t spawn_server(const std::vector<std::string>& args) {
    std::vector<std::string> all = {STRATA_SERVER_BINARY, "--log-level", "warn"};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    EXPECT_EQ(posix_spawn(&pid, STRATA_SERVER_BINARY, nullptr, nullptr, argv.data(), environ), 0);
    return pid;
}

/// Waits for the process to exit; returns its exit status, or -1 after `seconds`.
int wait_exit(pid_t pid, int seconds) {
    for (int i = 0; i < seconds * 100; ++i) {
        int status = 0;
        if (waitpid(pid, &status, WNOHANG) == pid)
            return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    return -1;
}

bool wait_live(int port) {
    httplib::Client c("127.0.0.1", port);
    for (int i = 0; i < 500; ++i) {
        if (auto r = c.Get("/livez"); r && r->status == 200) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

void finishes_in_flight_work_on(int signo) {
    const int port = free_port();
    const pid_t pid = spawn_server({"--demo", "--port", std::to_string(port)});
    ASSERT_TRUE(wait_live(port));
    // A large frame, so that the signal lands while it renders.
    auto slow = std::async(std::launch::async, [port] {
        httplib::Client c("127.0.0.1", port);
        c.set_read_timeout(120, 0);
        auto r = c.Get("/v1/render?width=2048&height=2048");
        return r ? r->status : 0;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
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
    ASSERT_TRUE(wait_live(port));
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

#pragma once
// The strata-server program as a child process: spawn it, wait for it, find it a free port.

#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>

extern char** environ;

namespace strata::server::test {

/// A loopback TCP port that nothing listens on (at the time of asking).
inline int free_port() {
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

/// Runs strata-server with `args` and this process's environment, where `env` ("NAME=value"
/// entries) replaces or adds variables; returns its pid.
inline pid_t spawn_server(const std::vector<std::string>& args,
                          const std::vector<std::string>& env = {}) {
    std::vector<std::string> all = {STRATA_SERVER_BINARY, "--log-level", "warn"};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);

    std::vector<std::string> vars = env;
    for (char** e = environ; *e != nullptr; ++e) {
        const std::string var = *e;
        const std::string name = var.substr(0, var.find('=') + 1);
        bool replaced = false;
        for (const auto& v : env) replaced = replaced || v.rfind(name, 0) == 0;
        if (!replaced) vars.push_back(var);
    }
    std::vector<char*> envp;
    for (auto& v : vars) envp.push_back(v.data());
    envp.push_back(nullptr);

    pid_t pid = 0;
    EXPECT_EQ(posix_spawn(&pid, STRATA_SERVER_BINARY, nullptr, nullptr, argv.data(), envp.data()),
              0);
    return pid;
}

/// Waits for the process to exit; returns its exit status, or -1 after `seconds`.
inline int wait_exit(pid_t pid, int seconds) {
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

/// Polls GET /readyz on the loopback port until it answers 200 (true) or 10 s pass (false).
/// Not /livez: that answers 200 as soon as the server listens, while it still loads its scene
/// and answers every other request 503.
inline bool wait_ready(int port) {
    httplib::Client c("127.0.0.1", port);
    for (int i = 0; i < 500; ++i) {
        if (auto r = c.Get("/readyz"); r && r->status == 200) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

/// The value of an unlabelled metric in GET /metrics, or -1 when it cannot be read.
inline double metric_value(int port, const std::string& name) {
    httplib::Client c("127.0.0.1", port);
    auto r = c.Get("/metrics");
    if (!r || r->status != 200) return -1;
    const std::string line = "\n" + name + " ";
    const auto at = r->body.find(line);
    return at == std::string::npos ? -1 : std::stod(r->body.substr(at + line.size()));
}

}  // namespace strata::server::test

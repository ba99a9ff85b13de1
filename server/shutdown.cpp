#include "server/shutdown.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <ctime>

#include <spdlog/spdlog.h>

namespace strata::server {

namespace {

sigset_t handled_set() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    sigaddset(&set, SIGUSR1);
    return set;
}

}  // namespace

ShutdownSignals::ShutdownSignals() {
    const sigset_t set = handled_set();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

ShutdownSignals::~ShutdownSignals() {
    m_done = true;
    if (m_waiter.joinable()) {
        pthread_kill(m_waiter.native_handle(), SIGUSR1);
        m_waiter.join();
    }
}

void ShutdownSignals::start(std::function<void(int)> on_signal,
                            std::chrono::milliseconds exit_after) {
    m_waiter = std::thread([this, on_signal = std::move(on_signal), exit_after] {
        const sigset_t set = handled_set();
        int stopping = 0;  // the first SIGINT or SIGTERM, once it came
        std::chrono::steady_clock::time_point exit_at{};
        for (;;) {
            int signo = 0;
            if (stopping == 0) {
                if (sigwait(&set, &signo) != 0) continue;
            } else {
                const auto left = std::max(std::chrono::steady_clock::duration::zero(),
                                           exit_at - std::chrono::steady_clock::now());
                const auto s = std::chrono::duration_cast<std::chrono::seconds>(left);
                const timespec wait{time_t(s.count()),
                                    long(std::chrono::nanoseconds(left - s).count())};
                signo = sigtimedwait(&set, nullptr, &wait);
                if (signo < 0 && errno == EAGAIN) {
                    static constexpr char LATE[] =
                        "graceful shutdown did not finish in time: exiting now\n";
                    [[maybe_unused]] const ssize_t n = ::write(2, LATE, sizeof LATE - 1);
                    ::_exit(128 + stopping);
                }
                if (signo < 0) continue;
            }
            if (m_done) return;
            if (signo == SIGHUP) {
                spdlog::info("SIGHUP received: ignored (no log files to reopen)");
            } else if ((signo == SIGINT || signo == SIGTERM) && stopping) {
                // Straight out, without destructors: the graceful path is what was refused.
                static constexpr char MESSAGE[] = "second signal: exiting now\n";
                [[maybe_unused]] const ssize_t n = ::write(2, MESSAGE, sizeof MESSAGE - 1);
                ::_exit(128 + signo);
            } else if (signo == SIGINT || signo == SIGTERM) {
                stopping = signo;
                exit_at = std::chrono::steady_clock::now() + exit_after;
                on_signal(signo);
            }
        }
    });
}

}  // namespace strata::server

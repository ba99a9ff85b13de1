#include "server/shutdown.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

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

void ShutdownSignals::start(std::function<void(int)> on_signal) {
    m_waiter = std::thread([this, on_signal = std::move(on_signal)] {
        const sigset_t set = handled_set();
        bool stopping = false;
        for (;;) {
            int signo = 0;
            if (sigwait(&set, &signo) != 0) continue;
            if (m_done) return;
            if (signo == SIGHUP) {
                spdlog::info("SIGHUP received: ignored (no log files to reopen)");
            } else if ((signo == SIGINT || signo == SIGTERM) && stopping) {
                // Straight out, without destructors: the graceful path is what was refused.
                static constexpr char MESSAGE[] = "second signal: exiting now\n";
                [[maybe_unused]] const ssize_t n = ::write(2, MESSAGE, sizeof MESSAGE - 1);
                ::_exit(128 + signo);
            } else if (signo == SIGINT || signo == SIGTERM) {
                stopping = true;
                on_signal(signo);
            }
        }
    });
}

}  // namespace strata::server

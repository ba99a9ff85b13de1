#include "server/shutdown.h"

#include <pthread.h>
#include <signal.h>

namespace strata::server {

namespace {

sigset_t shutdown_set() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGUSR1);
    return set;
}

}  // namespace

ShutdownSignals::ShutdownSignals() {
    const sigset_t set = shutdown_set();
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
        const sigset_t set = shutdown_set();
        for (;;) {
            int signo = 0;
            if (sigwait(&set, &signo) != 0) continue;
            if (m_done) return;
            if (signo == SIGINT || signo == SIGTERM) {
                m_done = true;
                on_signal(signo);
                return;
            }
        }
    });
}

}  // namespace strata::server

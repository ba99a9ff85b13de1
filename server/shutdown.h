#pragma once
// Signals without doing anything in a signal handler: SIGINT, SIGTERM and SIGHUP are blocked in
// every thread and a dedicated thread waits for them with sigwait().
//
//   - The first SIGINT or SIGTERM starts the graceful shutdown (on_signal).
//   - A second one ends the process at once, for an operator who does not want to wait.
//   - SIGHUP is logged and ignored: the server keeps no log files to reopen, and a hang-up of
//     the terminal that started it must not take its scenes down.

#include <atomic>
#include <functional>
#include <thread>

namespace strata::server {

class ShutdownSignals {
public:
    /// Blocks SIGINT, SIGTERM, SIGHUP (and SIGUSR1, used to wake the waiter) in the calling
    /// thread and in every thread it starts afterwards. Construct before starting any thread.
    ShutdownSignals();
    /// Wakes and joins the waiter.
    ~ShutdownSignals();
    ShutdownSignals(const ShutdownSignals&) = delete;
    ShutdownSignals& operator=(const ShutdownSignals&) = delete;

    /// Starts the waiter: `on_signal(signo)` runs once, on the waiter thread, at the first
    /// SIGINT or SIGTERM; a second one calls _exit(128 + signo).
    void start(std::function<void(int)> on_signal);

private:
    std::thread m_waiter;
    std::atomic<bool> m_done{false};
};

}  // namespace strata::server

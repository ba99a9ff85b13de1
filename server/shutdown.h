#pragma once
// Signals without doing anything in a signal handler: SIGINT, SIGTERM and SIGHUP are blocked in
// every thread and a dedicated thread waits for them with sigwait().
//
//   - The first SIGINT or SIGTERM starts the graceful shutdown (on_signal).
//   - A second one ends the process at once, for an operator who does not want to wait.
//   - So does the watchdog, when the graceful shutdown has not ended the process in time: a
//     thread stuck on a lock or a peer cannot keep a stopping server alive.
//   - SIGHUP is logged and ignored: the server keeps no log files to reopen, and a hang-up of
//     the terminal that started it must not take its scenes down.

#include <atomic>
#include <chrono>
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
    /// SIGINT or SIGTERM; a second one calls _exit(128 + signo), and so does `exit_after`
    /// passing after the first without the process having exited.
    void start(std::function<void(int)> on_signal, std::chrono::milliseconds exit_after);

private:
    std::thread m_waiter;
    std::atomic<bool> m_done{false};
};

}  // namespace strata::server

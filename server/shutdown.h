#pragma once
// Graceful shutdown on SIGTERM and SIGINT without doing anything in a signal handler: the signals
// are blocked in every thread and a dedicated thread waits for them with sigwait().

#include <atomic>
#include <functional>
#include <thread>

namespace strata::server {

class ShutdownSignals {
public:
    /// Blocks SIGINT, SIGTERM (and SIGUSR1, used to wake the waiter) in the calling thread and
    /// in every thread it starts afterwards. Construct before starting any thread.
    ShutdownSignals();
    /// Wakes and joins the waiter if no signal came.
    ~ShutdownSignals();
    ShutdownSignals(const ShutdownSignals&) = delete;
    ShutdownSignals& operator=(const ShutdownSignals&) = delete;

    /// Starts the waiter: `on_signal(signo)` runs once, on the waiter thread, at the first
    /// SIGINT or SIGTERM.
    void start(std::function<void(int)> on_signal);

private:
    std::thread m_waiter;
    std::atomic<bool> m_done{false};
};

}  // namespace strata::server

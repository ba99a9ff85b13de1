#pragma once
// Cooperative cancellation for long launches. The caller owns a CancelToken and hands the
// renderer a pointer to it; the tile loop polls it between packets and stops early. Another
// thread cancels it (the client went away, the server is shutting down), or a deadline passes.

#include <atomic>
#include <chrono>
#include <cstdint>

namespace strata {

/// Why a launch was asked to stop.
enum class CancelReason : uint8_t { None, ClientGone, Deadline, Shutdown };

/// "the client disconnected", "its deadline passed", "the server is shutting down".
inline const char* cancel_reason_text(CancelReason r) {
    switch (r) {
        case CancelReason::ClientGone:
            return "the client disconnected";
        case CancelReason::Deadline:
            return "its deadline passed";
        case CancelReason::Shutdown:
            return "the server is shutting down";
        case CancelReason::None:
            break;
    }
    return "it was not cancelled";
}

/// A stop flag with an optional deadline. Thread-safe; polling costs an atomic load and, while a
/// deadline is set, one steady-clock read.
class CancelToken {
public:
    using Clock = std::chrono::steady_clock;

    /// Asks the work to stop; the first reason given is the one reported.
    void cancel(CancelReason reason) { record(reason); }

    /// The work stops once `deadline` has passed (reported as CancelReason::Deadline).
    void set_deadline(Clock::time_point deadline) {
        m_deadline.store(deadline.time_since_epoch().count(), std::memory_order_relaxed);
    }

    /// Why to stop, or CancelReason::None to go on.
    CancelReason reason() const {
        const auto r = CancelReason(m_reason.load(std::memory_order_relaxed));
        if (r != CancelReason::None) return r;
        const Clock::rep deadline = m_deadline.load(std::memory_order_relaxed);
        if (deadline != NO_DEADLINE && Clock::now().time_since_epoch().count() >= deadline) {
            record(CancelReason::Deadline);
            return CancelReason(m_reason.load(std::memory_order_relaxed));
        }
        return CancelReason::None;
    }

    bool cancelled() const { return reason() != CancelReason::None; }

private:
    static constexpr Clock::rep NO_DEADLINE = INT64_MAX;

    /// Keeps the first reason. Const: a reader that finds the deadline passed records it, so
    /// that every later poll and the final report agree.
    void record(CancelReason reason) const {
        uint8_t none = uint8_t(CancelReason::None);
        m_reason.compare_exchange_strong(none, uint8_t(reason), std::memory_order_relaxed);
    }

    mutable std::atomic<uint8_t> m_reason{uint8_t(CancelReason::None)};
    std::atomic<Clock::rep> m_deadline{NO_DEADLINE};
};

/// True when `token` is set and asks to stop (a null token never does).
inline bool should_stop(const CancelToken* token) {
    return token != nullptr && token->cancelled();
}

}  // namespace strata

#pragma once
// Where a replica stands, shared by its reader, writer and snapshotter (replica.h): the applied
// and log versions, joined or stopped (and why), the lag, the counts; and the waits on them.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>

#include "server/replica/replica.h"
#include "server/replica/replica_util.h"

namespace strata::replica {

class ReplicaState {
public:
    /// `log`: the log's description (redis://host:port/stream), for messages.
    ReplicaState(std::string log, uint64_t version);

    uint64_t applied() const { return m_applied.load(); }
    uint64_t log_version() const { return m_log_version.load(); }
    bool joined() const { return m_joined.load(); }
    bool stopped() const { return m_stopped.load(); }
    bool shutting_down() const { return m_shutdown.load(); }
    const std::string& log() const { return m_log; }

    /// Raises the newest version the log is known to have.
    void raise_log_version(uint64_t v);
    void set_connected(bool connected) { m_connected = connected; }
    /// An entry was applied: the version, its count, the lag (`appended_ms`: when it was
    /// appended, 0 when unknown); wakes the waiters.
    void applied_entry(uint64_t version, int64_t appended_ms);
    /// An entry is waiting to be applied: the lag counts from its append, unless older ones wait.
    void entry_waiting(int64_t appended_ms);
    /// A snapshot was loaded in place of the scene (`jumped`: over a gap, not to join).
    void loaded_snapshot(uint64_t version, bool jumped);
    void mark_joined();
    /// Stops for good, logging why; every waiter wakes.
    void stop_loudly(const std::string& why);
    /// The error a write gets from a stopped replica, saying why it stopped.
    Unexpected<Error> stopped_error() const;
    /// Stops loudly when the log's `head` is behind the applied version (Redis was reset or
    /// lost entries this replica applied).
    Status check_not_behind(uint64_t head);
    void shut_down();

    /// False once shutting down.
    bool sleep_for(milliseconds d);
    /// Waits until the applied version is at least `version`; false on timeout or when the
    /// replica stopped.
    bool wait_applied(uint64_t version, milliseconds timeout);
    /// Waits until `deadline` for the reader to join the log; an error when the replica stopped
    /// or has not joined by then.
    Status wait_joined(Clock::time_point deadline);

    /// Counts under the lock: `count(&ReplicaStatus::appends)`.
    void count(uint64_t ReplicaStatus::*counter, uint64_t n = 1);
    void know_snapshot(uint64_t version);
    uint64_t known_snapshot() const { return m_known_snapshot.load(); }
    ReplicaStatus status() const;

private:
    const std::string m_log;
    std::atomic<uint64_t> m_applied;
    std::atomic<uint64_t> m_log_version;
    std::atomic<bool> m_joined{false};
    std::atomic<bool> m_stopped{false};
    std::atomic<bool> m_connected{false};
    std::atomic<bool> m_shutdown{false};
    std::atomic<int64_t> m_lag_since_ms{0};  ///< unix ms the oldest unapplied entry was appended
    std::atomic<uint64_t> m_known_snapshot{0};

    mutable std::mutex m_mutex;  ///< guards the fields below and pairs with m_cv
    std::condition_variable m_cv;
    std::string m_stop_reason;
    ReplicaStatus m_counters;  ///< the counting fields only
};

}  // namespace strata::replica

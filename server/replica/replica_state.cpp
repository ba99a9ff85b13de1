#include "server/replica/replica_state.h"

#include <spdlog/spdlog.h>

namespace strata::replica {

ReplicaState::ReplicaState(std::string log, uint64_t version)
    : m_log(std::move(log)), m_applied(version), m_log_version(version) {
    m_counters.log = m_log;
}

void ReplicaState::raise_log_version(uint64_t v) {
    uint64_t cur = m_log_version.load();
    while (v > cur && !m_log_version.compare_exchange_weak(cur, v)) {
    }
}

void ReplicaState::applied_entry(uint64_t version, int64_t appended_ms) {
    {
        std::lock_guard lock(m_mutex);
        m_applied = version;
        ++m_counters.entries_applied;
    }
    m_cv.notify_all();
    if (version >= m_log_version.load()) {
        m_lag_since_ms = 0;
    } else if (appended_ms) {
        m_lag_since_ms = appended_ms;
    }
}

void ReplicaState::entry_waiting(int64_t appended_ms) {
    if (m_lag_since_ms.load() == 0) m_lag_since_ms = appended_ms ? appended_ms : unix_ms();
}

void ReplicaState::loaded_snapshot(uint64_t version, bool jumped) {
    {
        std::lock_guard lock(m_mutex);
        m_applied = version;
        m_counters.snapshot_loaded_version = version;
        if (jumped) ++m_counters.snapshot_jumps;
    }
    m_cv.notify_all();
    raise_log_version(version);
}

void ReplicaState::mark_joined() {
    {
        std::lock_guard lock(m_mutex);
        m_joined = true;
    }
    m_cv.notify_all();
    spdlog::info("edit log {}: caught up at version {}; following", m_log, m_applied.load());
}

void ReplicaState::stop_loudly(const std::string& why) {
    {
        std::lock_guard lock(m_mutex);
        // Shutting down (the scene was deleted, the server stops): a log that went with it is
        // no news.
        if (m_stopped || m_shutdown) return;
        m_stop_reason = why;
        m_stopped = true;
    }
    m_cv.notify_all();
    spdlog::critical(
        "replica stopped: {}. It applies nothing more from {} and answers 503 to writes and "
        "/readyz; reads show version {}. Fix the log, then restart it.",
        why, m_log, m_applied.load());
}

Unexpected<Error> ReplicaState::stopped_error() const {
    std::lock_guard lock(m_mutex);
    return storage("this replica has stopped following the edit log: " + m_stop_reason);
}

Status ReplicaState::check_not_behind(uint64_t head) {
    const uint64_t applied = m_applied.load();
    if (head >= applied) return {};
    stop_loudly("the edit log ends at version " + std::to_string(head) +
                ", behind this replica's version " + std::to_string(applied) +
                " (was Redis reset, or did it lose acknowledged entries?)");
    return stopped_error();
}

void ReplicaState::shut_down() {
    {
        std::lock_guard lock(m_mutex);
        m_shutdown = true;
    }
    m_cv.notify_all();
}

bool ReplicaState::sleep_for(milliseconds d) {
    std::unique_lock lock(m_mutex);
    m_cv.wait_for(lock, d, [&] { return m_shutdown.load(); });
    return !m_shutdown.load();
}

bool ReplicaState::wait_applied(uint64_t version, milliseconds timeout) {
    std::unique_lock lock(m_mutex);
    return m_cv.wait_for(lock, timeout, [&] {
        return m_applied.load() >= version || m_stopped || m_shutdown;
    }) && m_applied.load() >= version;
}

Status ReplicaState::wait_joined(Clock::time_point deadline) {
    if (m_stopped) return stopped_error();
    {
        std::unique_lock lock(m_mutex);
        m_cv.wait_until(lock, deadline, [&] { return m_joined || m_stopped || m_shutdown; });
    }
    if (m_stopped) return stopped_error();
    if (!m_joined)
        return storage("this replica has not caught up with the edit log " + m_log +
                       " yet (is Redis reachable?)");
    return {};
}

void ReplicaState::count(uint64_t ReplicaStatus::*counter, uint64_t n) {
    std::lock_guard lock(m_mutex);
    m_counters.*counter += n;
}

void ReplicaState::know_snapshot(uint64_t version) {
    uint64_t cur = m_known_snapshot.load();
    while (version > cur && !m_known_snapshot.compare_exchange_weak(cur, version)) {
    }
}

ReplicaStatus ReplicaState::status() const {
    ReplicaStatus s;
    {
        std::lock_guard lock(m_mutex);
        s = m_counters;
        s.stop_reason = m_stop_reason;
    }
    s.connected = m_connected;
    s.joined = m_joined;
    s.stopped = m_stopped;
    s.applied_version = m_applied;
    s.log_version = std::max(m_log_version.load(), s.applied_version);
    s.lag_entries = s.log_version - s.applied_version;
    const int64_t since = m_lag_since_ms.load();
    s.lag_seconds =
        s.lag_entries > 0 && since > 0 ? std::max<int64_t>(0, unix_ms() - since) / 1e3 : 0.0;
    s.snapshot_version = std::max(s.snapshot_version, m_known_snapshot.load());
    return s;
}

}  // namespace strata::replica

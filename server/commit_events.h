#pragma once
// GET /v1/events: each commit that brought edits in becomes one `commit` event with its version
// and rebuild report, whoever caused it, sent to every event stream in order; a comment every
// 15 s keeps idle streams alive. Commits are queued by whoever commits (quick, any thread) and
// published on the stream hub's thread (stream_hub.h), so commits in quick succession are each
// reported.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "engine/engine.h"
#include "server/stream_channel.h"

namespace strata::server {

class CommitEvents {
public:
    using Clock = std::chrono::steady_clock;

    struct Stats {
        uint64_t clients = 0;         ///< event streams open now
        uint64_t events = 0;          ///< commit events (each sent to every client)
        uint64_t events_dropped = 0;  ///< dropped from a full queue (oldest first)
    };

    /// Commits up to `reported_version` are no events (a new stream's hello describes them).
    /// `poke` wakes the publishing thread; it is called outside this object's lock.
    CommitEvents(uint64_t reported_version, std::function<void()> poke);

    /// A new event stream; null once stopped.
    std::shared_ptr<StreamChannel> subscribe();
    /// Queues the event of a commit; commits at a version already reported are ignored.
    void on_commit(const RebuildReport& report);
    /// On the publishing thread: sends the queued events, and the keep-alive comment when due.
    void publish(Clock::time_point now);
    /// Ends every event stream; later subscriptions and commits are refused.
    void stop();

    bool has_clients() const;
    /// The newest commit that brought edits in, once there was one.
    std::optional<RebuildReport> last_commit() const;
    Stats stats() const;

private:
    std::function<void()> m_poke;
    mutable std::mutex m_mutex;
    bool m_stopped = false;
    std::vector<std::shared_ptr<StreamChannel>> m_clients;
    std::vector<RebuildReport> m_queue;
    uint64_t m_reported_version;  ///< of the newest event
    std::optional<RebuildReport> m_last_commit;
    Clock::time_point m_next_heartbeat{};
    Stats m_stats;
};

}  // namespace strata::server

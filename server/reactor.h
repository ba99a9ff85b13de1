#pragma once
// The front end: one epoll thread that owns every socket. It accepts connections (within a total
// and a per-client-address limit), reads each request with RequestReader under total deadlines
// (headers, whole request), answers refusals and the health endpoints itself, hands complete
// requests to the worker pool, and writes their answers without blocking. A worker is therefore
// busy only while a handler runs: slow, idle or hostile clients cost a file descriptor and their
// buffered bytes (also capped), never a thread.
//
// Connection life: Idle (between requests) -> Reading -> [Waiting] -> Busy (a worker has the
// request; the socket is watched only for the client leaving, which cancels a render) ->
// Writing -> Idle, or
// Lingering (write side shut, unread input discarded briefly so that the client reads the answer
// instead of a reset) -> closed. Requests pipelined on one connection are served in order.
// Waiting: a request asking for a min_version the scene has not reached is held here, not on
// a worker, until the version arrives or --min-version-wait-ms passes (then a worker answers,
// 503 when still behind); at most --max-waiting-reads in all and per client, one more gets 503.
// A worker may answer with a stream instead (Outcome::stream, stream_channel.h): the connection
// then goes Busy -> Streaming, where the reactor writes the channel's parts as the producer
// offers them, paced and bounded by the channel, until the client leaves, the producer ends the
// stream, or the drain ends it (then the part being written finishes and the connection closes).
//
// Shutdown (drain()): idle and half-read connections close at once, streams end; the listening
// socket stays open so that /readyz answers 503 (and /livez 200) while in-flight requests finish;
// after --shutdown-grace their renders are cancelled; run() returns once nothing is in flight, or
// a second later at the latest.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/core/cancel.h"
#include "engine/core/result.h"
#include "server/application.h"
#include "server/client_quota.h"
#include "server/front_end_counters.h"
#include "server/reactor_inbox.h"
#include "server/request_reader.h"
#include "server/server_config.h"
#include "server/stream_channel.h"
#include "server/waiting_reads.h"

namespace strata::server {

class ServerMetrics;

class Reactor {
public:
    /// Hands a request to a worker; the worker calls complete(conn, ...) with the answer.
    /// `close`: the answer must say `Connection: close`.
    using Dispatch = std::function<void(uint64_t conn, PreparedRequest&& request,
                                        std::shared_ptr<CancelToken> cancel, bool close)>;

    Reactor(const ServerConfig& config, ServerMetrics& metrics, Dispatch dispatch);
    ~Reactor();
    Reactor(const Reactor&) = delete;
    Reactor& operator=(const Reactor&) = delete;

    /// Sets up the event loop around the listening socket `listen_fd`; an error names the call
    /// that failed.
    Status open(int listen_fd);
    /// Serves connections until a drain has finished (at once when open() did not succeed).
    void run();
    /// Starts the graceful drain. Thread-safe, idempotent, callable before run().
    void drain();
    /// True once drain() was called.
    bool draining() const { return m_drain_requested.load(); }
    /// While true (recovering the data directory, then building its acceleration structures),
    /// /readyz answers 503 with `progress()` as its detail, and every other request but /livez
    /// gets 503 with Retry-After. `progress` is called on the reactor thread. Thread-safe.
    void set_starting(bool starting, std::function<std::string()> progress = {}) {
        {
            std::lock_guard lock(m_progress_mutex);
            if (progress) m_progress = std::move(progress);
        }
        m_starting.store(starting);
    }
    bool starting() const { return m_starting.load(); }
    /// A scene's version by name ("" for the default scene), for requests waiting for a
    /// min_version; called on the reactor thread, so it must not block. Set before run(), never
    /// after.
    void set_version_source(WaitingReads::VersionOf version) { m_version = std::move(version); }
    /// What else /readyz asks (request_reader.h); set before run(), never after.
    void set_readiness(std::function<Readiness()> readiness) { m_readiness = std::move(readiness); }
    /// A worker's answer for connection `conn`; `close`: close after writing it. A stream's
    /// head is written, then its parts. Thread-safe.
    void complete(uint64_t conn, Outcome outcome, bool close);

    const FrontEndCounters& counters() const { return m_counters; }

private:
    struct Connection;
    using Clock = std::chrono::steady_clock;

    void accept_ready(Clock::time_point now);
    void on_event(Connection& c, uint32_t events, Clock::time_point now);
    void read_from(Connection& c, Clock::time_point now);
    void advance(Connection& c, Clock::time_point now);
    void dispatch(Connection& c, PreparedRequest&& request);
    /// Dispatches `request`, or holds it (Waiting) while the scene is behind its min_version.
    void dispatch_or_wait(Connection& c, PreparedRequest&& request, Clock::time_point now);
    /// Dispatches the waiting requests whose version arrived or whose wait is over.
    void release_waiters(Clock::time_point now);
    void take_completions(Clock::time_point now);
    void answer(Connection& c, DirectAnswer&& a, Clock::time_point now);
    /// The access log and the response counters: every answer passes here once.
    void log_response(const Connection& c, int status, std::size_t bytes, Clock::time_point now);
    void start_write(Connection& c, std::string bytes, bool close, Clock::time_point now);
    void write_to(Connection& c, Clock::time_point now);
    void finish_response(Connection& c, Clock::time_point now);
    void linger(Connection& c, Clock::time_point now);
    void set_reading(Connection& c, Clock::time_point now);
    void account(Connection& c);
    void close(uint64_t id);
    void sweep(Clock::time_point now);
    void begin_drain(Clock::time_point now);
    bool drain_finished(Clock::time_point now) const;
    /// Changes the events epoll reports for `c`; false (logged) when that failed: close it.
    bool watch(const Connection& c, uint32_t events);
    void begin_stream(Connection& c, Outcome&& head, Clock::time_point now);
    void stream_write(Connection& c, Clock::time_point now);
    void on_stream_event(Connection& c, uint32_t events, Clock::time_point now);
    void take_ready_streams(Clock::time_point now);

    const ServerConfig& m_config;
    ReaderConfig m_reader_config;
    ServerMetrics& m_metrics;
    Dispatch m_dispatch;
    FrontEndCounters m_counters;

    ReactorInbox m_inbox;
    int m_epoll = -1;
    int m_listen = -1;
    bool m_accept_paused = false;
    Clock::time_point m_accept_resume{};

    std::unordered_map<uint64_t, std::unique_ptr<Connection>> m_connections;
    ClientQuota m_admission;  ///< open, unrestricted connections
    std::size_t m_open_restricted = 0;
    std::size_t m_buffered = 0;  ///< request bytes held over all connections
    uint64_t m_next_id = 2;      ///< 0 and 1 are the listening socket and the eventfd
    std::vector<char> m_scratch;

    std::atomic<bool> m_drain_requested{false};
    std::atomic<bool> m_starting{false};
    std::mutex m_progress_mutex;
    std::function<std::string()> m_progress;  ///< what starting is doing; guarded by the mutex
    std::function<Readiness()> m_readiness;   ///< set before run()
    WaitingReads::VersionOf m_version;        ///< set before run()
    WaitingReads m_waiting;
    bool m_draining = false;
    Clock::time_point m_grace_deadline{};
    Clock::time_point m_hard_deadline{};
    Clock::time_point m_last_sweep{};
};

}  // namespace strata::server

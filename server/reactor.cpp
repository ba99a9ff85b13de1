#include "server/reactor.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>

#include <spdlog/spdlog.h>

#include "protocol/problem.h"
#include "server/metrics.h"
#include "server/response_writer.h"
#include "server/request_target.h"
#include "server/scene_path.h"

namespace strata::server {

namespace {

constexpr uint64_t LISTEN_KEY = 0;
constexpr uint64_t WAKE_KEY = 1;
/// Connections beyond every limit still get this many slots, for health checks only.
constexpr std::size_t HEALTH_RESERVE = 16;
/// Deadline of a connection that is over a limit (it may only ask for /livez or /readyz).
constexpr std::chrono::seconds RESTRICTED_TIMEOUT{2};
/// How long a closing connection's unread input is discarded, and how much of it at most.
constexpr std::chrono::seconds LINGER_TIME{2};
constexpr std::size_t LINGER_BYTES = std::size_t(8) << 20;
/// Precision of every deadline.
constexpr std::chrono::milliseconds TICK{20};
/// A stream's socket send buffer. Frames a slow viewer has not taken wait in the stream's
/// channel (one pending, replaced by newer ones), not in the kernel: without a cap, send-buffer
/// autotuning would queue megabytes of stale frames per viewer.
constexpr int STREAM_SEND_BUFFER = 256 * 1024;
/// How often waiting reads look at the scene's version.
constexpr std::chrono::milliseconds WAIT_POLL{2};
/// How long accept() pauses when the process is out of file descriptors.
constexpr std::chrono::milliseconds ACCEPT_PAUSE{100};

/// The client's IP address, as connection limits count clients.
std::string client_address(const sockaddr_storage& addr) {
    char buf[INET6_ADDRSTRLEN] = {};
    if (addr.ss_family == AF_INET) {
        const auto& v4 = reinterpret_cast<const sockaddr_in&>(addr);
        inet_ntop(AF_INET, &v4.sin_addr, buf, sizeof buf);
    } else if (addr.ss_family == AF_INET6) {
        const auto& v6 = reinterpret_cast<const sockaddr_in6&>(addr);
        inet_ntop(AF_INET6, &v6.sin6_addr, buf, sizeof buf);
    }
    std::string ip = buf;
    // An IPv4 client of a dual-stack socket is the same client as over IPv4.
    if (ip.rfind("::ffff:", 0) == 0 && ip.find('.') != std::string::npos) ip.erase(0, 7);
    return ip;
}

double ms_since(std::chrono::steady_clock::time_point t,
                std::chrono::steady_clock::time_point now) {
    return std::chrono::duration<double, std::milli>(now - t).count();
}

/// A failed call's error as a Status naming the call.
Status syscall_failure(const char* call) {
    return failure(ErrorCode::Internal, std::string(call) + ": " + std::strerror(errno));
}

}  // namespace

struct Reactor::Connection {
    enum class Phase : uint8_t { Idle, Reading, Waiting, Busy, Writing, Lingering, Streaming };

    Connection(uint64_t id_, int fd_, std::string client_, const ReaderConfig& config)
        : id(id_), fd(fd_), client(std::move(client_)), reader(config) {}

    uint64_t id;
    int fd;
    std::string client;  ///< the client's IP address
    bool restricted = false;
    Phase phase = Phase::Idle;
    RequestReader reader;
    Clock::time_point deadline{};         ///< Idle, Waiting, Writing, Lingering; Reading: headers
    Clock::time_point idle_deadline{};    ///< an Idle connection's (blank lines: no later)
    Clock::time_point read_deadline{};    ///< Reading: the whole request
    Clock::time_point started{};          ///< first byte of the current request
    std::shared_ptr<CancelToken> cancel;  ///< Busy
    std::string method = "-";             ///< of the current request, for the access log
    std::string path = "-";
    bool keep_alive = true;  ///< for the request a worker has
    bool peer_gone = false;
    std::string out;
    std::size_t out_pos = 0;
    bool close_after = false;
    std::size_t served = 0;
    std::size_t in_flight = 0;              ///< bytes of the request a worker has
    std::size_t accounted = 0;              ///< what this connection adds to Reactor::m_buffered
    std::size_t discarded = 0;              ///< Lingering, Streaming
    std::shared_ptr<StreamChannel> stream;  ///< Streaming
    StreamChannel::Part part;               ///< Streaming: the part being written
    std::size_t part_pos = 0;
    Clock::time_point next_part{};  ///< Streaming: no part starts before (the channel's pace)
    uint32_t watching = 0;          ///< Streaming: the events epoll watches
};

Reactor::Reactor(const ServerConfig& config, ServerMetrics& metrics, Dispatch dispatch)
    : m_config(config),
      m_metrics(metrics),
      m_dispatch(std::move(dispatch)),
      m_admission(config.max_connections, config.max_connections_per_client),
      m_scratch(64 * 1024),
      m_waiting(config.max_waiting_reads, config.max_waiting_reads_per_client) {
    m_reader_config.limits.max_head_bytes = config.max_header_bytes;
    m_reader_config.limits.max_headers = config.max_headers;
    m_reader_config.limits.max_target_bytes = config.max_uri_bytes;
    m_reader_config.limits.max_body_bytes = config.max_body_bytes;
    m_reader_config.token = config.token;
    m_reader_config.tokens = config.tokens;
    // The command line checked it (cli.cpp); a policy that does not parse allows no origin.
    if (auto cors = CorsPolicy::parse(config.cors_origin)) m_reader_config.cors = cors.value();
}

Reactor::~Reactor() {
    for (auto& [id, c] : m_connections) {
        if (c->stream) c->stream->detach();
        ::close(c->fd);
    }
    if (m_epoll >= 0) ::close(m_epoll);
}

void Reactor::drain() {
    m_drain_requested = true;
    m_inbox.wake();
}

void Reactor::complete(uint64_t conn, Outcome outcome, bool close) {
    m_inbox.post({conn, std::move(outcome), close});
}

bool Reactor::watch(const Connection& c, uint32_t events) {
    epoll_event ev{};
    ev.events = events;
    ev.data.u64 = c.id;
    if (epoll_ctl(m_epoll, EPOLL_CTL_MOD, c.fd, &ev) == 0) return true;
    spdlog::error("connection {} ({}): epoll_ctl(MOD): {}; closing it", c.id, c.client,
                  std::strerror(errno));
    return false;
}

Status Reactor::open(int listen_fd) {
    m_listen = listen_fd;
    const int flags = fcntl(m_listen, F_GETFL);
    if (flags < 0 || fcntl(m_listen, F_SETFL, flags | O_NONBLOCK) < 0)
        return syscall_failure("fcntl(O_NONBLOCK) on the listening socket");
    const Result<int> wake = m_inbox.fd();
    if (!wake) return Unexpected(wake.error());
    m_epoll = epoll_create1(EPOLL_CLOEXEC);
    if (m_epoll < 0) return syscall_failure("epoll_create1");
    for (const auto& [fd, key] : {std::pair(m_listen, LISTEN_KEY), std::pair(*wake, WAKE_KEY)}) {
        epoll_event ev{};
        ev.events = EPOLLIN;
        ev.data.u64 = key;
        if (epoll_ctl(m_epoll, EPOLL_CTL_ADD, fd, &ev) < 0)
            return syscall_failure("epoll_ctl(ADD) of the listening socket or the eventfd");
    }
    return {};
}

void Reactor::run() {
    if (m_epoll < 0) return;  // open() failed or was never called: nothing to serve
    std::vector<epoll_event> events(256);
    for (;;) {
        const int timeout = int((m_waiting.empty() ? TICK : WAIT_POLL).count());
        const int n = epoll_wait(m_epoll, events.data(), int(events.size()), timeout);
        if (n < 0 && errno != EINTR) {
            spdlog::critical("epoll_wait: {}; the front end stops", std::strerror(errno));
            break;
        }
        const Clock::time_point now = Clock::now();
        for (int i = 0; i < n; ++i) {
            const uint64_t key = events[i].data.u64;
            if (key == LISTEN_KEY) {
                accept_ready(now);
            } else if (key == WAKE_KEY) {
                m_inbox.clear_wake();
            } else if (auto it = m_connections.find(key); it != m_connections.end()) {
                on_event(*it->second, events[i].events, now);
            }
        }
        take_completions(now);
        take_ready_streams(now);
        if (m_drain_requested && !m_draining) begin_drain(now);
        release_waiters(now);
        if (now - m_last_sweep >= TICK) sweep(now);
        if (m_draining && drain_finished(now)) break;
    }
    std::vector<uint64_t> ids;
    for (const auto& [id, c] : m_connections) ids.push_back(id);
    for (uint64_t id : ids) close(id);
}

void Reactor::accept_ready(Clock::time_point now) {
    for (;;) {
        sockaddr_storage addr{};
        socklen_t len = sizeof addr;
        const int fd = accept4(m_listen, reinterpret_cast<sockaddr*>(&addr), &len,
                               SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            if (errno == EINTR || errno == ECONNABORTED) continue;
            if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
                // Out of descriptors: stop polling the listener for a moment instead of spinning.
                spdlog::warn("accept: {}; pausing new connections", std::strerror(errno));
                if (epoll_ctl(m_epoll, EPOLL_CTL_DEL, m_listen, nullptr) < 0)
                    spdlog::error("epoll_ctl(DEL) of the listening socket: {}",
                                  std::strerror(errno));
                m_accept_paused = true;
                m_accept_resume = now + ACCEPT_PAUSE;
            }
            return;
        }
        std::string client = client_address(addr);
        const bool over = !m_admission.admits(client);
        if (over && m_open_restricted >= HEALTH_RESERVE) {
            ++m_counters.connections_refused;
            ::close(fd);
            continue;
        }
        const int one = 1;
        if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) < 0)
            spdlog::debug("setsockopt(TCP_NODELAY): {}", std::strerror(errno));
        const uint64_t id = m_next_id++;
        epoll_event ev{};
        ev.events = EPOLLIN | EPOLLRDHUP;
        ev.data.u64 = id;
        if (epoll_ctl(m_epoll, EPOLL_CTL_ADD, fd, &ev) < 0) {
            spdlog::error("connection from {}: epoll_ctl(ADD): {}; closing it", client,
                          std::strerror(errno));
            ::close(fd);
            continue;
        }
        auto c = std::make_unique<Connection>(id, fd, std::move(client), m_reader_config);
        c->restricted = over;
        if (over) {
            ++m_open_restricted;
            ++m_counters.connections_restricted;
            c->deadline = now + RESTRICTED_TIMEOUT;
        } else {
            m_admission.take(c->client);
            c->deadline = now + std::chrono::seconds(m_config.header_timeout_s);
        }
        c->idle_deadline = c->deadline;
        ++m_counters.connections_accepted;
        ++m_counters.connections_open;
        m_connections.emplace(id, std::move(c));
    }
}

void Reactor::on_event(Connection& c, uint32_t events, Clock::time_point now) {
    using Phase = Connection::Phase;
    switch (c.phase) {
        case Phase::Idle:
        case Phase::Reading:
            read_from(c, now);
            return;
        case Phase::Waiting:
            // Watched with EPOLLONESHOT for the client leaving: nobody is left to answer.
            if (events & (EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
                ++m_counters.clients_gone;
                close(c.id);
            }
            return;
        case Phase::Busy:
            // Watched with EPOLLONESHOT for this alone: the client hung up, so whatever its
            // request still computes is wasted.
            if (events & (EPOLLRDHUP | EPOLLHUP | EPOLLERR)) {
                c.peer_gone = true;
                ++m_counters.clients_gone;
                if (c.cancel) c.cancel->cancel(CancelReason::ClientGone);
            }
            return;
        case Phase::Writing:
            if (events & (EPOLLERR | EPOLLHUP)) return close(c.id);
            write_to(c, now);
            return;
        case Phase::Streaming:
            return on_stream_event(c, events, now);
        case Phase::Lingering: {
            const ssize_t n = ::recv(c.fd, m_scratch.data(), m_scratch.size(), 0);
            if (n < 0 && (errno == EAGAIN || errno == EINTR)) return;
            c.discarded += n > 0 ? std::size_t(n) : 0;
            if (n <= 0 || c.discarded > LINGER_BYTES) close(c.id);
            return;
        }
    }
}

void Reactor::read_from(Connection& c, Clock::time_point now) {
    const ssize_t n = ::recv(c.fd, m_scratch.data(), m_scratch.size(), 0);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return;
    if (n <= 0) return close(c.id);  // the client left (or reset); there is nobody to answer
    if (m_buffered + std::size_t(n) > m_config.max_buffered_bytes) {
        DirectAnswer a;
        a.status = 503;
        a.bytes = problem_bytes(
            protocol::make_problem(protocol::ProblemType::Unavailable,
                                   "the server holds too much unfinished request data from other "
                                   "clients (--max-buffered-mb); retry later"),
            true);
        return answer(c, std::move(a), now);
    }
    if (c.phase == Connection::Phase::Idle) set_reading(c, now);
    c.reader.append(m_scratch.data(), std::size_t(n));
    advance(c, now);
}

void Reactor::set_reading(Connection& c, Clock::time_point now) {
    c.phase = Connection::Phase::Reading;
    c.started = now;
    c.deadline =
        now + (c.restricted ? RESTRICTED_TIMEOUT : std::chrono::seconds(m_config.header_timeout_s));
    c.read_deadline = now + std::chrono::seconds(m_config.read_timeout_s);
}

void Reactor::advance(Connection& c, Clock::time_point now) {
    for (;;) {
        ReaderSituation situation{m_draining, c.restricted, m_starting.load(), {}, &m_readiness};
        if (situation.starting) {
            std::lock_guard lock(m_progress_mutex);
            if (m_progress) situation.progress = m_progress();
        }
        ReaderStep step = c.reader.next(situation);
        account(c);
        switch (step.kind) {
            case ReaderStep::Kind::NeedMore:
                if (c.phase == Connection::Phase::Reading && !c.reader.mid_request()) {
                    // Only blank lines came (the reader drops them): still idle, no later.
                    c.phase = Connection::Phase::Idle;
                    c.deadline = c.idle_deadline;
                }
                return;
            case ReaderStep::Kind::Continue: {
                static constexpr std::string_view CONTINUE = "HTTP/1.1 100 Continue\r\n\r\n";
                // 25 bytes on a socket whose send buffer is empty (nothing else is in flight).
                if (::send(c.fd, CONTINUE.data(), CONTINUE.size(), MSG_NOSIGNAL | MSG_DONTWAIT) !=
                    ssize_t(CONTINUE.size()))
                    return close(c.id);
                continue;
            }
            case ReaderStep::Kind::Answer:
                return answer(c, std::move(step.answer), now);
            case ReaderStep::Kind::Request:
                return dispatch_or_wait(c, std::move(step.request), now);
        }
    }
}

void Reactor::log_response(const Connection& c, int status, std::size_t bytes,
                           Clock::time_point now) {
    m_metrics.count_response(status);
    spdlog::info("{} {} {} {}B {:.2f}ms", c.method, c.path, status, bytes,
                 c.method == "-" ? 0.0 : ms_since(c.started, now));
}

void Reactor::answer(Connection& c, DirectAnswer&& a, Clock::time_point now) {
    c.method = std::move(a.method);
    c.path = std::move(a.path);
    log_response(c, a.status, a.bytes.size(), now);
    const bool keep =
        !a.close && !m_draining && !c.restricted && c.served + 1 < m_config.max_keep_alive_requests;
    start_write(c, std::move(a.bytes), !keep, now);
}

void Reactor::dispatch(Connection& c, PreparedRequest&& request) {
    c.phase = Connection::Phase::Busy;
    c.cancel = std::make_shared<CancelToken>();
    c.keep_alive =
        request.keep_alive && !m_draining && c.served + 1 < m_config.max_keep_alive_requests;
    c.in_flight = request.http.held_bytes();
    c.method = request.http.method;
    c.path = request.http.path;
    account(c);
    if (!watch(c, EPOLLRDHUP | EPOLLONESHOT)) return close(c.id);
    ++m_counters.requests_in_flight;
    m_dispatch(c.id, std::move(request), c.cancel, !c.keep_alive);
}

void Reactor::dispatch_or_wait(Connection& c, PreparedRequest&& request, Clock::time_point now) {
    const std::optional<HttpRequest::MinVersion> asked = request.http.min_version();
    // A malformed value is the route's 400; a reached one, or no wait allowed, runs at once.
    if (!asked || !asked->valid || !m_version || m_draining || m_config.min_version_wait_ms == 0)
        return dispatch(c, std::move(request));
    const std::optional<ScenePath> scoped = scene_path(request.http.path);
    std::string scene = scoped ? decode_path_segment(scoped->scene) : std::string();
    if (scene == "default") scene.clear();
    if (m_version(scene) >= asked->version) return dispatch(c, std::move(request));
    if (!m_waiting.admits(c.client)) {
        ++m_counters.waits_refused;
        protocol::ApiResponse refusal = protocol::problem_response(protocol::make_problem(
            protocol::ProblemType::Unavailable, m_waiting.refusal(c.client)));
        refusal.headers.emplace_back("Retry-After", "1");
        DirectAnswer a;
        a.status = refusal.status;
        a.method = request.http.method;
        a.path = request.http.path;
        a.close = !request.keep_alive;
        a.bytes = write_response(
            refusal, Framing{a.close, request.http.method == "HEAD", request.cors_origin});
        return answer(c, std::move(a), now);
    }
    c.phase = Connection::Phase::Waiting;
    c.in_flight = request.http.held_bytes();
    account(c);
    ++m_counters.reads_waiting;
    m_waiting.park({c.id, c.client, std::move(scene), asked->version,
                    now + std::chrono::milliseconds(m_config.min_version_wait_ms),
                    std::move(request)});
    if (!watch(c, EPOLLRDHUP | EPOLLONESHOT)) close(c.id);
}

void Reactor::release_waiters(Clock::time_point now) {
    if (m_waiting.empty()) return;
    for (WaitingReads::Waiter& w : m_waiting.take_due(m_version, now, m_draining)) {
        --m_counters.reads_waiting;
        // A worker answers now: the version arrived, or it says how far behind the scene is.
        auto it = m_connections.find(w.conn);
        if (it != m_connections.end()) dispatch(*it->second, std::move(w.request));
    }
}

void Reactor::take_completions(Clock::time_point now) {
    for (ReactorInbox::Completion& d : m_inbox.take_completions()) {
        --m_counters.requests_in_flight;
        auto it = m_connections.find(d.conn);
        if (it == m_connections.end()) continue;  // closed at the drain's hard deadline
        Connection& c = *it->second;
        c.cancel.reset();
        c.in_flight = 0;
        account(c);
        log_response(c, d.outcome.status, d.outcome.bytes.size(), now);
        if (d.outcome.stream) {
            if (c.peer_gone) {
                d.outcome.stream->detach();
                close(c.id);
                continue;
            }
            begin_stream(c, std::move(d.outcome), now);
            continue;
        }
        const bool close = d.close || !c.keep_alive || m_draining || c.peer_gone;
        start_write(c, std::move(d.outcome.bytes), close, now);
    }
}

void Reactor::start_write(Connection& c, std::string bytes, bool close, Clock::time_point now) {
    c.phase = Connection::Phase::Writing;
    c.out = std::move(bytes);
    c.out_pos = 0;
    c.close_after = close;
    c.deadline = now + std::chrono::seconds(m_config.write_timeout_s);
    write_to(c, now);
}

void Reactor::write_to(Connection& c, Clock::time_point now) {
    while (c.out_pos < c.out.size()) {
        const ssize_t n = ::send(c.fd, c.out.data() + c.out_pos, c.out.size() - c.out_pos,
                                 MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) {
            c.out_pos += std::size_t(n);
        } else if (n < 0 && errno == EINTR) {
            continue;
        } else if (n < 0 && errno == EAGAIN) {
            if (!watch(c, EPOLLOUT)) close(c.id);
            return;
        } else {
            return close(c.id);
        }
    }
    finish_response(c, now);
}

void Reactor::finish_response(Connection& c, Clock::time_point now) {
    c.out = std::string();
    ++c.served;
    if (c.close_after) return linger(c, now);
    c.phase = Connection::Phase::Idle;
    c.idle_deadline = c.deadline = now + std::chrono::seconds(m_config.keep_alive_timeout_s);
    if (c.reader.mid_request()) set_reading(c, now);  // pipelined: its bytes are already here
    if (!watch(c, EPOLLIN | EPOLLRDHUP)) return close(c.id);
    advance(c, now);
}

void Reactor::linger(Connection& c, Clock::time_point now) {
    // Closing with unread input would reset the connection, and the client could lose the answer
    // before reading it: shut the write side, then read and discard until it closes too.
    if (::shutdown(c.fd, SHUT_WR) < 0) return close(c.id);  // the peer is gone already
    c.phase = Connection::Phase::Lingering;
    c.deadline = now + LINGER_TIME;
    c.reader.discard();
    account(c);
    if (!watch(c, EPOLLIN | EPOLLRDHUP)) close(c.id);
}

void Reactor::account(Connection& c) {
    const std::size_t held = c.reader.buffered_bytes() + c.in_flight;
    m_buffered = m_buffered + held - c.accounted;
    c.accounted = held;
}

void Reactor::close(uint64_t id) {
    auto it = m_connections.find(id);
    if (it == m_connections.end()) return;
    Connection& c = *it->second;
    if (c.phase == Connection::Phase::Waiting) {
        m_waiting.forget(c.id);
        --m_counters.reads_waiting;
    }
    if (c.cancel) c.cancel->cancel(CancelReason::ClientGone);
    if (c.stream) c.stream->detach();
    // Closing the descriptor removes it from the epoll set anyway; a failure here is only logged.
    if (epoll_ctl(m_epoll, EPOLL_CTL_DEL, c.fd, nullptr) < 0)
        spdlog::debug("connection {}: epoll_ctl(DEL): {}", c.id, std::strerror(errno));
    ::close(c.fd);
    m_buffered -= c.accounted;
    if (c.restricted) {
        --m_open_restricted;
    } else {
        m_admission.give_back(c.client);
    }
    --m_counters.connections_open;
    m_connections.erase(it);
}

void Reactor::sweep(Clock::time_point now) {
    using Phase = Connection::Phase;
    m_last_sweep = now;
    if (m_accept_paused && now >= m_accept_resume) {
        epoll_event ev{};
        ev.events = EPOLLIN;
        ev.data.u64 = LISTEN_KEY;
        if (epoll_ctl(m_epoll, EPOLL_CTL_ADD, m_listen, &ev) == 0) {
            m_accept_paused = false;
        } else {
            spdlog::error("epoll_ctl(ADD) of the listening socket: {}; retrying",
                          std::strerror(errno));
            m_accept_resume = now + ACCEPT_PAUSE;
        }
    }
    std::vector<uint64_t> expired;
    for (auto& [id, c] : m_connections) {
        if (c->phase == Phase::Waiting) continue;  // release_waiters() ends the wait
        if (c->phase == Phase::Busy) {
            if (m_draining && now >= m_grace_deadline && c->cancel)
                c->cancel->cancel(CancelReason::Shutdown);
            continue;
        }
        if (c->phase == Phase::Streaming) {
            // Late only while a write makes no progress: a viewer may watch for hours.
            const bool writing = c->out_pos < c->out.size() || c->part;
            if (writing && now >= c->deadline) expired.push_back(id);
            continue;
        }
        const bool late =
            c->phase == Phase::Reading
                ? now >= c->read_deadline || (!c->reader.reading_body() && now >= c->deadline)
                : now >= c->deadline;
        if (late) expired.push_back(id);
    }
    for (uint64_t id : expired) {
        Connection& c = *m_connections.at(id);
        if (c.phase != Phase::Reading) {
            if (c.phase == Phase::Writing || c.phase == Phase::Streaming) ++m_counters.timeouts;
            close(id);
            continue;
        }
        ++m_counters.timeouts;
        const bool body = c.reader.reading_body();
        DirectAnswer a;
        a.status = 408;
        protocol::Problem p = protocol::make_problem(
            protocol::ProblemType::RequestTimeout,
            body ? "the request body did not arrive within " +
                       std::to_string(m_config.read_timeout_s) + " s (--read-timeout)"
                 : "the request headers did not arrive within " +
                       std::to_string(c.restricted ? RESTRICTED_TIMEOUT.count()
                                                   : m_config.header_timeout_s) +
                       " s (--header-timeout)");
        a.bytes = problem_bytes(p, true);
        answer(c, std::move(a), now);
    }
    // Streams whose next part waited for its pace.
    std::vector<uint64_t> paced;
    for (auto& [id, c] : m_connections) {
        if (c->phase == Phase::Streaming && !c->part && c->out_pos >= c->out.size() &&
            now >= c->next_part)
            paced.push_back(id);
    }
    for (uint64_t id : paced) {
        if (auto it = m_connections.find(id); it != m_connections.end())
            stream_write(*it->second, now);
    }
}

void Reactor::begin_drain(Clock::time_point now) {
    m_draining = true;
    m_grace_deadline = now + std::chrono::seconds(m_config.shutdown_grace_s);
    m_hard_deadline = m_grace_deadline + std::chrono::seconds(1);
    std::vector<uint64_t> idle;
    for (const auto& [id, c] : m_connections) {
        if (c->phase == Connection::Phase::Idle || c->phase == Connection::Phase::Reading)
            idle.push_back(id);
    }
    for (uint64_t id : idle) close(id);
    // Streams end: the part being written finishes, then the connection closes.
    std::vector<uint64_t> streams;
    for (const auto& [id, c] : m_connections) {
        if (c->phase == Connection::Phase::Streaming) streams.push_back(id);
    }
    for (uint64_t id : streams) {
        Connection& c = *m_connections.at(id);
        c.stream->end();
        stream_write(c, now);
    }
}

bool Reactor::drain_finished(Clock::time_point now) const {
    if (now >= m_hard_deadline) return true;
    for (const auto& [id, c] : m_connections) {
        if (c->phase == Connection::Phase::Waiting || c->phase == Connection::Phase::Busy ||
            c->phase == Connection::Phase::Writing || c->phase == Connection::Phase::Streaming)
            return false;
    }
    return true;
}

void Reactor::begin_stream(Connection& c, Outcome&& head, Clock::time_point now) {
    c.phase = Connection::Phase::Streaming;
    c.stream = std::move(head.stream);
    c.out = std::move(head.bytes);
    c.out_pos = 0;
    c.close_after = true;
    c.next_part = now;
    c.deadline = now + std::chrono::seconds(m_config.write_timeout_s);
    c.watching = 0;
    if (::setsockopt(c.fd, SOL_SOCKET, SO_SNDBUF, &STREAM_SEND_BUFFER, sizeof STREAM_SEND_BUFFER) <
        0)
        spdlog::debug("setsockopt(SO_SNDBUF): {}", std::strerror(errno));
    const uint64_t id = c.id;
    c.stream->attach([this, id] { m_inbox.post_stream(id); });
    if (m_draining) c.stream->end();
    stream_write(c, now);
}

void Reactor::take_ready_streams(Clock::time_point now) {
    for (uint64_t id : m_inbox.take_streams()) {
        auto it = m_connections.find(id);
        if (it == m_connections.end()) continue;
        Connection& c = *it->second;
        // A part in progress takes the next one itself when it is done.
        if (c.phase == Connection::Phase::Streaming && !c.part && c.out_pos >= c.out.size())
            stream_write(c, now);
    }
}

void Reactor::stream_write(Connection& c, Clock::time_point now) {
    const auto watch_for = [&](uint32_t events) {
        if (c.watching != events && !watch(c, events)) return close(c.id);
        c.watching = events;
    };
    for (;;) {
        const std::string* buf = nullptr;
        std::size_t* pos = nullptr;
        if (c.out_pos < c.out.size()) {
            buf = &c.out;
            pos = &c.out_pos;
        } else if (c.part && c.part_pos < c.part->size()) {
            buf = c.part.get();
            pos = &c.part_pos;
        } else {
            if (c.part) {
                c.part.reset();
                c.stream->written();
            }
            if (c.stream->ended()) {
                // The producer or the drain ended it: close as any answer with Connection: close.
                c.stream->detach();
                c.stream.reset();
                c.out = std::string();
                c.out_pos = 0;
                c.phase = Connection::Phase::Writing;
                return finish_response(c, now);
            }
            if (now < c.next_part) return watch_for(EPOLLIN | EPOLLRDHUP);  // sweep() resumes
            StreamChannel::Part next = c.stream->take();
            if (!next) return watch_for(EPOLLIN | EPOLLRDHUP);
            c.part = std::move(next);
            c.part_pos = 0;
            c.next_part = now + c.stream->min_interval();
            c.deadline = now + std::chrono::seconds(m_config.write_timeout_s);
            continue;
        }
        const ssize_t n =
            ::send(c.fd, buf->data() + *pos, buf->size() - *pos, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) {
            *pos += std::size_t(n);
            c.deadline = now + std::chrono::seconds(m_config.write_timeout_s);
        } else if (n < 0 && errno == EINTR) {
            continue;
        } else if (n < 0 && errno == EAGAIN) {
            return watch_for(EPOLLIN | EPOLLRDHUP | EPOLLOUT);
        } else {
            return close(c.id);
        }
    }
}

void Reactor::on_stream_event(Connection& c, uint32_t events, Clock::time_point now) {
    if (events & (EPOLLRDHUP | EPOLLHUP | EPOLLERR)) return close(c.id);
    if (events & EPOLLIN) {
        // A streaming client has nothing more to say: whatever it sends is read and dropped,
        // and an end of input means it left.
        const ssize_t n = ::recv(c.fd, m_scratch.data(), m_scratch.size(), 0);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) return close(c.id);
        c.discarded += n > 0 ? std::size_t(n) : 0;
        if (c.discarded > LINGER_BYTES) return close(c.id);
    }
    if (events & EPOLLOUT) stream_write(c, now);
}

}  // namespace strata::server

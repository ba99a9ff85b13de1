#include "server/commit_events.h"

#include <algorithm>
#include <string>

#include "protocol/report_json.h"
#include "protocol/safe_text.h"

namespace strata::server {

namespace {

/// Event streams get a comment this often, so that proxies and the front end notice a client
/// that left even when nothing is committed.
constexpr std::chrono::seconds HEARTBEAT{15};
/// Commit events waiting for the publishing thread, at most.
constexpr std::size_t MAX_QUEUED = 1024;

}  // namespace

CommitEvents::CommitEvents(uint64_t reported_version, std::function<void()> poke)
    : m_poke(std::move(poke)), m_reported_version(reported_version) {}

std::shared_ptr<StreamChannel> CommitEvents::subscribe() {
    auto channel = std::make_shared<StreamChannel>(StreamChannel::Mode::Queue);
    {
        std::lock_guard lock(m_mutex);
        if (m_stopped) return nullptr;
        m_clients.push_back(channel);
    }
    m_poke();  // from the quiet pace to the busy one
    return channel;
}

void CommitEvents::on_commit(const RebuildReport& report) {
    {
        std::lock_guard lock(m_mutex);
        if (m_stopped || report.version <= m_reported_version) return;
        m_reported_version = report.version;
        m_last_commit = report;
        if (m_clients.empty()) return;  // a new client's hello carries the last one
        // The publishing thread may be busy for seconds (a viewer render) while clients commit:
        // the queue is bounded (the oldest go first, and the count says so).
        if (m_queue.size() >= MAX_QUEUED) {
            m_queue.erase(m_queue.begin());
            ++m_stats.events_dropped;
        }
        m_queue.push_back(report);
    }
    m_poke();
}

void CommitEvents::publish(Clock::time_point now) {
    std::vector<RebuildReport> reports;
    std::vector<std::shared_ptr<StreamChannel>> clients;
    {
        std::lock_guard lock(m_mutex);
        m_clients.erase(std::remove_if(m_clients.begin(), m_clients.end(),
                                       [](const auto& c) { return c->gone(); }),
                        m_clients.end());
        clients = m_clients;
        reports.swap(m_queue);
        m_stats.events += reports.size();
    }
    if (clients.empty()) return;
    for (const RebuildReport& r : reports) {
        const protocol::Json data = {{"version", r.version},
                                     {"report", protocol::report_to_json(r)}};
        auto event = std::make_shared<const std::string>(
            "id: " + std::to_string(r.version) +
            "\nevent: commit\ndata: " + protocol::dump_json(data) + "\n\n");
        for (auto& c : clients) c->offer(event);
    }
    if (now >= m_next_heartbeat) {
        m_next_heartbeat = now + HEARTBEAT;
        auto ping = std::make_shared<const std::string>(": keep-alive\n\n");
        for (auto& c : clients) c->offer(ping);
    }
}

void CommitEvents::stop() {
    std::vector<std::shared_ptr<StreamChannel>> clients;
    {
        std::lock_guard lock(m_mutex);
        m_stopped = true;
        clients.swap(m_clients);
    }
    for (auto& c : clients) c->end();
}

bool CommitEvents::has_clients() const {
    std::lock_guard lock(m_mutex);
    return !m_clients.empty();
}

std::optional<RebuildReport> CommitEvents::last_commit() const {
    std::lock_guard lock(m_mutex);
    return m_last_commit;
}

CommitEvents::Stats CommitEvents::stats() const {
    std::lock_guard lock(m_mutex);
    Stats s = m_stats;
    s.clients = uint64_t(std::count_if(m_clients.begin(), m_clients.end(),
                                       [](const auto& c) { return !c->gone(); }));
    return s;
}

}  // namespace strata::server

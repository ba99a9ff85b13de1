#include "server/stream_hub.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "engine/image/jpeg_encode.h"
#include "protocol/json_document.h"
#include "protocol/report_json.h"

namespace strata::server {

namespace {

/// How long the thread sleeps when nothing wakes it (the pace of progressive refinement and of
/// retrying a render the API deferred).
constexpr std::chrono::milliseconds IDLE_WAIT{10};
/// The same with no stream open: only commits are watched for (the first event describes the
/// state anyway).
constexpr std::chrono::milliseconds QUIET_WAIT{250};
/// Event streams get a comment this often, so that proxies and the front end notice a client
/// that left even when nothing is committed.
constexpr std::chrono::seconds HEARTBEAT{15};

/// One frame: the JPEG, then the next boundary and the next part's headers at once. A browser
/// shows a part only once the next part's headers arrive (Chromium finishes an image part
/// there), so they cannot wait for the next frame; the frame's version and sample count travel
/// inside the JPEG instead, as a comment (COM segment) "strata version=V samples=S".
std::string frame_part(const std::string& jpeg, uint64_t version, uint32_t samples) {
    const std::string comment =
        "strata version=" + std::to_string(version) + " samples=" + std::to_string(samples);
    const std::size_t length = comment.size() + 2;  // a segment length counts itself
    std::string part;
    part.reserve(jpeg.size() + comment.size() + 64);
    part.append(jpeg, 0, 2);  // SOI
    part += "\xFF\xFE";
    part += char(length >> 8);
    part += char(length & 0xFF);
    part += comment;
    part.append(jpeg, 2, std::string::npos);
    part += STREAM_PART_SEPARATOR;
    return part;
}

/// Drops the channels whose client left; returns how many remain.
std::size_t prune(std::vector<std::shared_ptr<StreamChannel>>& channels) {
    channels.erase(
        std::remove_if(channels.begin(), channels.end(), [](const auto& c) { return c->gone(); }),
        channels.end());
    return channels.size();
}

}  // namespace

void write_stream_metrics(std::string& out, const StreamHubStats& s) {
    auto line = [&](const char* name, const char* type, const char* help, uint64_t v) {
        out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" +
               name + " " + std::to_string(v) + "\n";
    };
    line("strata_stream_viewers", "gauge", "Open frame streams (GET /v1/stream).", s.viewers);
    line("strata_stream_views", "gauge", "Distinct views those streams render.", s.views);
    line("strata_stream_event_clients", "gauge", "Open event streams (GET /v1/events).",
         s.event_clients);
    line("strata_stream_frames_rendered_total", "counter",
         "Viewer renders (each shared by the viewers of its view).", s.frames_rendered);
    line("strata_stream_frames_sent_total", "counter", "Frames handed to viewers.",
         s.frames_offered);
    line("strata_stream_render_errors_total", "counter", "Viewer renders that failed.",
         s.render_errors);
    line("strata_stream_commit_events_total", "counter", "Commit events published.",
         s.events_published);
    line("strata_stream_renders_deferred_total", "counter",
         "Times a due viewer render waited for API renders or commits.", s.deferred_for_api);
}

StreamHub::StreamHub(Engine& engine, std::function<bool()> api_busy)
    : m_engine(engine), m_api_busy(std::move(api_busy)) {
    // Commits before the hub existed are no events (the first event, hello, describes them).
    m_commits_seen = m_engine.counters().commits;
    m_reported_version = m_engine.last_report().version;
    m_thread = std::thread([this] { run(); });
}

StreamHub::~StreamHub() {
    join();
}

std::shared_ptr<StreamChannel> StreamHub::watch(ViewerSpec spec, std::string head) {
    const auto interval = std::chrono::milliseconds(int64_t(1000.0 / spec.fps));
    auto channel =
        std::make_shared<StreamChannel>(StreamChannel::Mode::Latest, std::move(head), interval);
    std::lock_guard lock(m_mutex);
    if (m_stopping) return nullptr;
    View& view = m_views[spec.key];
    if (view.viewers.empty()) {
        view.spec = std::move(spec);
    } else {
        // The view renders as often as its most eager viewer; each is paced by its channel.
        view.spec.fps = std::max(view.spec.fps, spec.fps);
    }
    if (view.last) channel->offer(view.last);  // something to show at once
    view.viewers.push_back(channel);
    ++m_stats.viewers;
    m_poked = true;
    m_wake.notify_one();
    return channel;
}

std::shared_ptr<StreamChannel> StreamHub::subscribe(std::string head) {
    auto channel = std::make_shared<StreamChannel>(StreamChannel::Mode::Queue, std::move(head));
    std::lock_guard lock(m_mutex);
    if (m_stopping) return nullptr;
    m_event_clients.push_back(channel);
    m_poked = true;  // from the quiet pace to the busy one
    m_wake.notify_one();
    return channel;
}

void StreamHub::on_commit(const RebuildReport& report) {
    std::lock_guard lock(m_mutex);
    if (m_stopping || report.version <= m_reported_version) return;
    m_reported_version = report.version;
    m_last_commit = report;
    m_reports.push_back(report);
    m_poked = true;
    m_wake.notify_one();
}

void StreamHub::stop() {
    std::vector<std::shared_ptr<StreamChannel>> all;
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping) return;
        m_stopping = true;
        for (auto& [key, view] : m_views)
            all.insert(all.end(), view.viewers.begin(), view.viewers.end());
        all.insert(all.end(), m_event_clients.begin(), m_event_clients.end());
        m_views.clear();
        m_event_clients.clear();
    }
    m_cancel.cancel(CancelReason::Shutdown);
    m_wake.notify_all();
    for (auto& c : all) c->end();
}

void StreamHub::join() {
    stop();
    if (m_thread.joinable()) m_thread.join();
}

StreamHubStats StreamHub::stats() const {
    std::lock_guard lock(m_mutex);
    StreamHubStats s = m_stats;
    s.viewers = 0;
    for (const auto& [key, view] : m_views) {
        for (const auto& c : view.viewers) {
            if (c->gone()) continue;
            ++s.viewers;
            s.frames_dropped += c->dropped();
            s.held_bytes += c->held_bytes();
        }
    }
    s.views = m_views.size();
    s.event_clients = 0;
    for (const auto& c : m_event_clients) s.event_clients += c->gone() ? 0 : 1;
    return s;
}

RebuildReport StreamHub::last_commit() const {
    {
        std::lock_guard lock(m_mutex);
        if (m_last_commit) return *m_last_commit;
    }
    return m_engine.last_report();
}

uint64_t StreamHub::scene_version() const {
    return m_engine.read([](const Scene& s) { return s.version(); });
}

void StreamHub::run() {
    std::unique_lock lock(m_mutex);
    while (!m_stopping) {
        const bool quiet = m_views.empty() && m_event_clients.empty();
        m_wake.wait_for(lock, quiet ? QUIET_WAIT : IDLE_WAIT,
                        [&] { return m_stopping || m_poked; });
        m_poked = false;
        if (m_stopping) break;
        lock.unlock();
        poll_commits();
        lock.lock();
        std::vector<RebuildReport> reports;
        reports.swap(m_reports);
        lock.unlock();
        const Clock::time_point now = Clock::now();
        publish_events(std::move(reports), now);
        // Renders one view at a time, so that events go out between frames.
        const bool rendered = render_one(now);
        lock.lock();
        if (rendered) m_poked = true;  // another view may be due as well
    }
}

void StreamHub::poll_commits() {
    const uint64_t commits = m_engine.counters().commits;
    if (commits == m_commits_seen) return;
    m_commits_seen = commits;
    on_commit(m_engine.last_report());
}

void StreamHub::publish_events(std::vector<RebuildReport> reports, Clock::time_point now) {
    std::vector<std::shared_ptr<StreamChannel>> clients;
    {
        std::lock_guard lock(m_mutex);
        prune(m_event_clients);
        clients = m_event_clients;
        m_stats.events_published += reports.size();
    }
    if (clients.empty()) return;
    for (const RebuildReport& r : reports) {
        const protocol::Json data = {{"version", r.version},
                                     {"report", protocol::report_to_json(r)}};
        auto event = std::make_shared<const std::string>(
            "id: " + std::to_string(r.version) + "\nevent: commit\ndata: " + data.dump() + "\n\n");
        for (auto& c : clients) c->offer(event);
    }
    if (now >= m_next_heartbeat) {
        m_next_heartbeat = now + HEARTBEAT;
        auto ping = std::make_shared<const std::string>(": keep-alive\n\n");
        for (auto& c : clients) c->offer(ping);
    }
}

bool StreamHub::render_one(Clock::time_point now) {
    // Step: pick the most overdue view that needs a frame.
    {
        std::lock_guard lock(m_mutex);
        if (m_views.empty()) return false;
    }
    const uint64_t version = scene_version();
    std::string key;
    ViewerSpec spec;
    {
        std::lock_guard lock(m_mutex);
        Clock::time_point oldest = Clock::time_point::max();
        for (auto it = m_views.begin(); it != m_views.end();) {
            if (prune(it->second.viewers) == 0) {
                it = m_views.erase(it);
                continue;
            }
            View& v = it->second;
            const bool stale = v.version != version;
            const bool improvable =
                !stale && v.samples < v.spec.max_samples && v.launches < v.spec.max_samples;
            const bool due = (stale || improvable) && v.failed_version != version &&
                             now >= v.next_render && v.next_render < oldest;
            if (due) {
                oldest = v.next_render;
                key = it->first;
            }
            ++it;
        }
        if (key.empty()) return false;
        if (m_api_busy && m_api_busy()) {
            ++m_stats.deferred_for_api;
            return false;
        }
        spec = m_views.at(key).spec;
    }

    // Step: render (accumulating) and encode, outside the lock.
    RenderRequest request = spec.request;
    request.accumulate = true;
    request.cancel = &m_cancel;
    auto frame = m_engine.render_frame(request);
    Result<std::string> jpeg =
        frame ? encode_jpeg_linear(frame->buffers.color.data(), frame->buffers.width,
                                   frame->buffers.height, request.exposure, spec.quality)
              : Result<std::string>(Unexpected(frame.error()));

    // Step: hand the frame to the view's viewers.
    std::vector<std::shared_ptr<StreamChannel>> viewers;
    StreamChannel::Part part;
    {
        std::lock_guard lock(m_mutex);
        auto it = m_views.find(key);
        if (it == m_views.end() || m_stopping) return true;
        View& v = it->second;
        v.next_render = now + std::chrono::milliseconds(int64_t(1000.0 / v.spec.fps));
        if (!jpeg) {
            // Retried once the scene changes (a camera override the new camera makes valid).
            ++m_stats.render_errors;
            v.failed_version = version;
            spdlog::warn("viewer render failed: {}", jpeg.error().message);
            return true;
        }
        ++m_stats.frames_rendered;
        const FrameInfo& info = frame->info;
        if (info.report.version > m_reported_version) {
            m_reported_version = info.report.version;
            m_last_commit = info.report;
            m_reports.push_back(info.report);
            m_poked = true;
        }
        v.launches = info.version == v.version ? v.launches + 1 : 1;
        v.version = info.version;
        v.samples = info.samples;
        part = std::make_shared<const std::string>(
            frame_part(jpeg.value(), info.version, info.samples));
        v.last = part;
        viewers = v.viewers;
        m_stats.frames_offered += viewers.size();
    }
    for (auto& c : viewers) c->offer(part);
    return true;
}

}  // namespace strata::server

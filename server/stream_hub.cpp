#include "server/stream_hub.h"

#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>

#include "engine/image/highlight.h"
#include "engine/image/jpeg_encode.h"
#include "engine/image/tonemap.h"
#include "protocol/json_document.h"
#include "protocol/report_json.h"
#include "protocol/safe_text.h"

namespace strata::server {

namespace {

/// How long the thread sleeps when nothing wakes it (the pace of progressive refinement and of
/// retrying a render the API deferred).
constexpr std::chrono::milliseconds IDLE_WAIT{10};
/// The same with no stream open (commits wake the thread themselves).
constexpr std::chrono::milliseconds QUIET_WAIT{250};

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

/// Drops a view's watchers whose client left; returns how many remain.
template <class W>
std::size_t prune_watchers(std::vector<W>& watchers) {
    watchers.erase(std::remove_if(watchers.begin(), watchers.end(),
                                  [](const W& w) { return w.channel->gone(); }),
                   watchers.end());
    return watchers.size();
}

}  // namespace

std::size_t view_bytes(const ViewerSpec& spec) {
    return std::size_t(spec.request.width) * spec.request.height * 8;
}

StreamHub::StreamHub(Engine& engine, std::function<bool()> api_busy, std::size_t max_view_bytes)
    : m_engine(engine),
      m_api_busy(std::move(api_busy)),
      m_max_view_bytes(max_view_bytes),
      // Commits before the hub existed are no events (the first event, hello, describes them).
      m_events(engine.last_report().version, [this] { poke(); }) {
    m_engine.set_commit_listener([this](const RebuildReport& r) { on_commit(r); });
    m_thread = std::thread([this] { run(); });
}

StreamHub::~StreamHub() {
    join();
}

Result<std::shared_ptr<StreamChannel>> StreamHub::watch(ViewerSpec spec) {
    const auto interval = std::chrono::milliseconds(int64_t(1000.0 / spec.fps));
    auto channel = std::make_shared<StreamChannel>(StreamChannel::Mode::Latest, interval);
    const std::string highlight = spec.highlight;
    std::lock_guard lock(m_mutex);
    if (m_stopping) return std::shared_ptr<StreamChannel>();
    if (!m_views.count(spec.key)) {
        // A new view: the views streams still watch, and this one, within the budget.
        std::size_t held = 0;
        for (auto it = m_views.begin(); it != m_views.end();) {
            if (prune_watchers(it->second.viewers) == 0) {
                it = m_views.erase(it);
                continue;
            }
            held += view_bytes(it->second.spec);
            ++it;
        }
        if (held + view_bytes(spec) > m_max_view_bytes) {
            ++m_stats.views_refused;
            return failure(
                ErrorCode::TooLarge,
                "a new view of " + std::to_string(spec.request.width) + "x" +
                    std::to_string(spec.request.height) + " would take the open " +
                    "streams' views to " + std::to_string((held + view_bytes(spec)) >> 20) +
                    " MiB, over --max-stream-mb (" + std::to_string(m_max_view_bytes >> 20) +
                    " MiB): watch a smaller frame, or the view of a stream already open");
        }
    }
    View& view = m_views[spec.key];
    if (view.viewers.empty()) {
        view.spec = std::move(spec);
    } else {
        // The view renders as often as its most eager viewer; each is paced by its channel.
        view.spec.fps = std::max(view.spec.fps, spec.fps);
    }
    Watcher watcher{channel, highlight};
    if (auto it = view.parts.find(watcher.highlight); it != view.parts.end()) {
        channel->offer(it->second);  // something to show at once
    } else if (view.frame) {
        watcher.needs_frame = true;  // the hub's thread encodes the newest frame for it
    }
    view.viewers.push_back(std::move(watcher));
    ++m_stats.viewers;
    m_poked = true;
    m_wake.notify_one();
    return channel;
}

void StreamHub::poke() {
    std::lock_guard lock(m_mutex);
    m_poked = true;
    m_wake.notify_one();
}

std::shared_ptr<StreamChannel> StreamHub::subscribe() {
    return m_events.subscribe();
}

void StreamHub::on_commit(const RebuildReport& report) {
    m_events.on_commit(report);
}

void StreamHub::stop() {
    // First: once this returns, no commit calls on_commit any more.
    m_engine.set_commit_listener(nullptr);
    std::vector<std::shared_ptr<StreamChannel>> all;
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping) return;
        m_stopping = true;
        for (auto& [key, view] : m_views)
            for (auto& w : view.viewers) all.push_back(w.channel);
        m_views.clear();
    }
    m_events.stop();
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
        s.view_bytes += view_bytes(view.spec);
        for (const auto& w : view.viewers) {
            const auto& c = w.channel;
            if (c->gone()) continue;
            ++s.viewers;
            s.frames_dropped += c->dropped();
            s.held_bytes += c->held_bytes();
        }
    }
    s.views = m_views.size();
    const CommitEvents::Stats events = m_events.stats();
    s.event_clients = events.clients;
    s.commit_events = events.events;
    s.commit_events_dropped = events.events_dropped;
    return s;
}

RebuildReport StreamHub::last_commit() const {
    return m_events.last_commit().value_or(m_engine.last_report());
}

uint64_t StreamHub::scene_version() const {
    return m_engine.read([](const Scene& s) { return s.version(); });
}

void StreamHub::run() {
    std::unique_lock lock(m_mutex);
    while (!m_stopping) {
        const bool quiet = m_views.empty() && !m_events.has_clients();
        m_wake.wait_for(lock, quiet ? QUIET_WAIT : IDLE_WAIT,
                        [&] { return m_stopping || m_poked; });
        m_poked = false;
        if (m_stopping) break;
        lock.unlock();
        const Clock::time_point now = Clock::now();
        m_events.publish(now);
        // Renders one view at a time, so that events go out between frames.
        const bool served = serve_joiners();
        const bool rendered = render_one(now) || served;
        lock.lock();
        if (rendered) m_poked = true;  // another view may be due as well
    }
}

bool StreamHub::render_one(Clock::time_point now) {
    // Step: pick the most overdue view that needs a frame.
    {
        std::lock_guard lock(m_mutex);
        if (m_views.empty()) return false;
    }
    const uint64_t version = scene_version();
    std::optional<ViewPick> pick = pick_view(version, now);
    if (!pick) return false;

    // Step: render (accumulating), outside the lock; the first launch of a version traces ids.
    RenderRequest request = pick->spec.request;
    request.accumulate = true;
    request.cancel = &m_cancel;
    if (!pick->previous) {
        request.format = ImageFormat::Exr;  // AOVs are listed with EXR only; nothing encodes it
        request.aovs = {Aov::InstanceId};
    }
    Engine& engine = pick->spec.past ? *pick->spec.past : m_engine;
    auto frame = engine.render_frame(request);

    // Step: tone-map once, then one JPEG per distinct highlight.
    RenderedFrame rendered = encode_render(frame, request.exposure, *pick);

    // Step: hand the frame to the view's viewers.
    offer_render(pick->key, pick->version, now, frame, std::move(rendered));
    return true;
}

bool StreamHub::wants_frame(const View& view, uint64_t version) {
    const bool stale = view.version != version;
    // A frame without ids (an edit raced the launch meant to trace them) while a viewer
    // highlights: one more launch traces them, even past max_samples.
    const bool needs_ids = view.frame && !view.frame->ids &&
                           std::any_of(view.viewers.begin(), view.viewers.end(),
                                       [](const Watcher& w) { return !w.highlight.empty(); });
    const bool improvable =
        !stale &&
        ((view.samples < view.spec.max_samples && view.launches < view.spec.max_samples) ||
         needs_ids);
    return stale || improvable;
}

std::optional<StreamHub::ViewPick> StreamHub::pick_view(uint64_t version, Clock::time_point now) {
    std::lock_guard lock(m_mutex);
    std::string key;
    Clock::time_point oldest = Clock::time_point::max();
    for (auto it = m_views.begin(); it != m_views.end();) {
        if (prune_watchers(it->second.viewers) == 0) {
            it = m_views.erase(it);
            continue;
        }
        const View& v = it->second;
        const uint64_t shown = v.spec.past ? v.spec.past->version() : version;
        const bool due = wants_frame(v, shown) && v.failed_version != shown &&
                         now >= v.next_render && v.next_render < oldest;
        if (due) {
            oldest = v.next_render;
            key = it->first;
        }
        ++it;
    }
    if (key.empty()) return std::nullopt;
    if (m_api_busy && m_api_busy()) {
        ++m_stats.renders_deferred;
        return std::nullopt;
    }
    const View& chosen = m_views.at(key);
    std::optional<ViewPick> pick(std::in_place);
    pick->spec = chosen.spec;
    pick->version = chosen.spec.past ? chosen.spec.past->version() : version;
    for (const Watcher& w : chosen.viewers) pick->highlights.insert(w.highlight);
    if (chosen.frame && chosen.frame->version == pick->version && chosen.frame->ids)
        pick->previous = chosen.frame;
    pick->key = std::move(key);
    return pick;
}

std::shared_ptr<StreamHub::ViewFrame> StreamHub::tone_map_frame(
    Frame& frame, float exposure, const std::shared_ptr<const ViewFrame>& previous) {
    auto f = std::make_shared<ViewFrame>();
    FrameBuffers& b = frame.buffers;
    f->width = b.width;
    f->height = b.height;
    f->version = frame.info.version;
    f->samples = frame.info.samples;
    f->rgb.resize(std::size_t(b.width) * b.height * 3);
    tonemap_to_srgb8(b.color.data(), b.pixel_count(), exposure, f->rgb.data());
    if (!b.instance_id.empty()) {
        f->ids = std::make_shared<const std::vector<uint32_t>>(std::move(b.instance_id));
        f->names = std::make_shared<const std::vector<std::pair<uint32_t, std::string>>>(
            std::move(frame.names.instances));
    } else if (previous && previous->version == f->version) {
        f->ids = previous->ids;
        f->names = previous->names;
    }
    return f;
}

StreamHub::RenderedFrame StreamHub::encode_render(Result<Frame>& frame, float exposure,
                                                  const ViewPick& pick) {
    RenderedFrame rendered;
    if (!frame) {
        rendered.status = Unexpected(frame.error());
        return rendered;
    }
    rendered.frame = tone_map_frame(frame.value(), exposure, pick.previous);
    for (const std::string& h : pick.highlights) {
        auto part = encode_part(*rendered.frame, h, pick.spec.quality);
        if (!part) {
            rendered.status = Unexpected(part.error());
            break;
        }
        rendered.parts[h] = std::move(part.value());
    }
    return rendered;
}

void StreamHub::offer_render(const std::string& key, uint64_t version, Clock::time_point now,
                             const Result<Frame>& frame, RenderedFrame&& rendered) {
    std::vector<std::pair<std::shared_ptr<StreamChannel>, StreamChannel::Part>> offers;
    std::optional<RebuildReport> committed;  // the render's own commit is an event too
    {
        std::lock_guard lock(m_mutex);
        auto it = m_views.find(key);
        if (it == m_views.end() || m_stopping) return;
        View& v = it->second;
        v.next_render = now + std::chrono::milliseconds(int64_t(1000.0 / v.spec.fps));
        if (!rendered.status) {
            // Retried once the scene changes (a camera override the new camera makes valid).
            ++m_stats.render_errors;
            v.failed_version = version;
            spdlog::warn("viewer render failed: {}", rendered.status.error().message);
            return;
        }
        ++m_stats.frames_rendered;
        const FrameInfo& info = frame->info;
        // A past version's first build is no commit of the scene.
        if (!v.spec.past) committed = info.report;
        v.launches = info.version == v.version ? v.launches + 1 : 1;
        v.version = info.version;
        v.samples = info.samples;
        v.frame = rendered.frame;
        v.parts = std::move(rendered.parts);
        for (Watcher& w : v.viewers) {
            auto p = v.parts.find(w.highlight);
            if (p == v.parts.end()) {
                w.needs_frame = true;  // joined during the render with a new highlight
                continue;
            }
            w.needs_frame = false;
            offers.emplace_back(w.channel, p->second);
        }
        m_stats.frames_sent += offers.size();
    }
    if (committed) m_events.on_commit(*committed);
    for (auto& [c, part] : offers) c->offer(part);
}

Result<StreamChannel::Part> StreamHub::encode_part(const ViewFrame& frame,
                                                   const std::string& highlight, int quality) {
    Result<std::string> jpeg = [&]() -> Result<std::string> {
        if (highlight.empty() || !frame.ids)
            return encode_jpeg(frame.rgb.data(), frame.width, frame.height, quality);
        // The slot that shows the instance in this frame; none when it is not in view.
        uint32_t slot = MISS_ID;
        for (const auto& [s, id] : *frame.names) {
            if (id == highlight) slot = s;
        }
        std::vector<uint8_t> rgb = frame.rgb;
        highlight_instance(rgb.data(), frame.ids->data(), frame.width, frame.height, slot);
        {
            std::lock_guard lock(m_mutex);
            ++m_stats.highlight_encodes;
        }
        return encode_jpeg(rgb.data(), frame.width, frame.height, quality);
    }();
    if (!jpeg) return Unexpected(jpeg.error());
    return StreamChannel::Part(std::make_shared<const std::string>(
        frame_part(jpeg.value(), frame.version, frame.samples)));
}

bool StreamHub::serve_joiners() {
    // Step: what waits: (view, highlight) pairs and the frame to encode for them.
    struct Job {
        std::string key, highlight;
        std::shared_ptr<const ViewFrame> frame;
        int quality = 75;
    };
    std::vector<Job> jobs;
    {
        std::lock_guard lock(m_mutex);
        for (auto& [view_key, v] : m_views) {
            if (!v.frame) continue;
            // A plain reference: lambdas cannot capture structured bindings before clang 16.
            const std::string& key = view_key;
            for (const Watcher& w : v.viewers) {
                if (!w.needs_frame) continue;
                const bool queued = std::any_of(jobs.begin(), jobs.end(), [&](const Job& j) {
                    return j.key == key && j.highlight == w.highlight;
                });
                if (!queued) jobs.push_back({key, w.highlight, v.frame, v.spec.quality});
            }
        }
    }
    if (jobs.empty()) return false;

    // Step: encode outside the lock; offer only if no newer frame came meanwhile (that one
    // served them).
    for (const Job& job : jobs) {
        auto part = encode_part(*job.frame, job.highlight, job.quality);
        std::vector<std::shared_ptr<StreamChannel>> to;
        {
            std::lock_guard lock(m_mutex);
            auto it = m_views.find(job.key);
            if (it == m_views.end() || it->second.frame != job.frame) continue;
            View& v = it->second;
            if (!part) {
                ++m_stats.render_errors;
                spdlog::warn("viewer frame encoding failed: {}", part.error().message);
            } else {
                v.parts[job.highlight] = part.value();
            }
            for (Watcher& w : v.viewers) {
                if (!w.needs_frame || w.highlight != job.highlight) continue;
                w.needs_frame = false;
                if (part) to.push_back(w.channel);
            }
            m_stats.frames_sent += to.size();
        }
        for (auto& c : to) c->offer(part.value());
    }
    return true;
}

}  // namespace strata::server

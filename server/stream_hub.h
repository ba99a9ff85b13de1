#pragma once
// The live viewer's producer: renders frames for GET /v1/stream and publishes commit events for
// GET /v1/events, into StreamChannels the front end writes (stream_channel.h).
//
// Frames. Viewers asking for the same view (the same render parameters) share one render per
// (scene version, view): a render happens only when the scene version moved or progressive
// accumulation can still improve the frame (up to max_samples), never more often than the
// fastest of those viewers asked (fps), and not at all when nothing changed. Every viewer render
// runs on the hub's one thread - viewers together hold one render slot - and it waits while any
// API render or commit is queued or running, so API clients go first: one waits at most for the
// viewer frame in progress. Renders use the engine's render path (Engine::render_frame with the
// request GET /v1/render parses, accumulating) and are encoded as JPEG (jpeg_encode.h).
//
// Highlight. A viewer may name a selected instance (`highlight`): its frames tint exactly the
// pixels whose instance_id AOV is that instance (engine/image/highlight.h). The highlight is not
// part of the view: the render stays shared and each distinct highlight gets its own JPEG of it.
// The ids come from the pixel-centre ray, the same for every launch of one accumulation, so the
// first launch at a version traces them and later launches reuse them. A viewer that joins with
// a highlight the newest frame was not encoded for gets that frame encoded for it, so a new
// selection shows at once, without a render, even when accumulation has ended. An instance the
// frame does not show (removed since, hidden, off screen) tints nothing.
//
// Events. The hub is the engine's commit listener and runs the publishing of commit events
// (commit_events.h) on its thread, between frames; its own renders' commits are events too.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/cancel.h"
#include "engine/engine.h"
#include "server/commit_events.h"
#include "server/stream_channel.h"

namespace strata::server {

/// What ends every frame and starts the next part: the boundary and the part's headers.
inline constexpr const char* STREAM_PART_SEPARATOR =
    "\r\n--strata-frame\r\nContent-Type: image/jpeg\r\n\r\n";

/// What one viewer watches.
struct ViewerSpec {
    RenderRequest request;      ///< each launch: size, spp, exposure, camera override
    int quality = 75;           ///< JPEG quality, 1..100
    double fps = 10.0;          ///< most frames per second this viewer is sent
    uint32_t max_samples = 16;  ///< accumulation stops improving the frame here
    std::string key;            ///< viewers with equal keys share renders
    std::string highlight;      ///< instance id whose pixels are tinted; "" for none
    /// The scene at a past version (at_version), held while the view is open; null: the live
    /// scene. Its frames accumulate up to max_samples and then stay as they are.
    std::shared_ptr<Engine> past;
};

/// Cumulative counts, for /metrics and tests.
struct StreamHubStats {
    uint64_t viewers = 0;          ///< frame streams open now
    uint64_t event_clients = 0;    ///< event streams open now
    uint64_t views = 0;            ///< distinct views rendered for now
    uint64_t frames_rendered = 0;  ///< viewer renders (each shared by its view's viewers)
    uint64_t frames_sent = 0;      ///< frames handed to viewers' channels
    uint64_t render_errors = 0;
    uint64_t commit_events = 0;          ///< commit events (each sent to every event client)
    uint64_t commit_events_dropped = 0;  ///< dropped from a full queue (oldest first)
    uint64_t renders_deferred = 0;       ///< times a due viewer render waited for API renders
    uint64_t frames_dropped = 0;         ///< frames open viewers missed (a newer one replaced them)
    uint64_t highlight_encodes = 0;      ///< JPEGs encoded with a highlight (one per frame and id)
    std::size_t held_bytes = 0;  ///< frame bytes held for open viewers (pending and writing)
    std::size_t view_bytes = 0;  ///< what the open views hold (view_bytes of each)
    uint64_t views_refused = 0;  ///< streams refused: their view was over the budget
};

/// The memory a view of `spec` holds at its frame size: the tone-mapped frame (3 bytes a
/// pixel), its instance ids (4) and its JPEGs (about 1).
std::size_t view_bytes(const ViewerSpec& spec);

class StreamHub {
public:
    /// `api_busy`: true while an API render or commit is queued or running. `max_view_bytes`:
    /// the memory the views of open streams may hold together (view_bytes each).
    StreamHub(Engine& engine, std::function<bool()> api_busy,
              std::size_t max_view_bytes = std::size_t(1) << 30);
    ~StreamHub();
    StreamHub(const StreamHub&) = delete;
    StreamHub& operator=(const StreamHub&) = delete;

    /// A new frame stream; null once stopped. A view no stream watches yet is refused
    /// (TooLarge) when its memory would take the views over the hub's budget.
    Result<std::shared_ptr<StreamChannel>> watch(ViewerSpec spec);
    /// A new event stream; null once stopped.
    std::shared_ptr<StreamChannel> subscribe();
    /// Queues a commit event (quick, any thread); commits at a version already reported are
    /// ignored.
    void on_commit(const RebuildReport& report);

    /// Ends every stream and stops rendering (a viewer render in progress is cancelled).
    /// Idempotent, thread-safe.
    void stop();
    /// stop(), then waits for the hub's thread.
    void join();

    StreamHubStats stats() const;
    /// The report of the newest commit that brought edits in (no-change commits, which every
    /// launch makes, do not replace it), or the engine's last report before the first.
    RebuildReport last_commit() const;

private:
    using Clock = std::chrono::steady_clock;
    /// One viewer of a view.
    struct Watcher {
        std::shared_ptr<StreamChannel> channel;
        std::string highlight;
        bool needs_frame = false;  ///< joined after the newest frame; not encoded for it yet
    };
    /// The newest frame of a view, kept to encode it for viewers that join with another
    /// highlight.
    struct ViewFrame {
        uint32_t width = 0, height = 0;
        uint64_t version = 0;
        uint32_t samples = 0;
        std::vector<uint8_t> rgb;  ///< tone-mapped, no highlight
        /// instance_id AOV and the ids of its slots; shared by the frames of one accumulation
        /// (null only when an edit raced the launch that should have traced them).
        std::shared_ptr<const std::vector<uint32_t>> ids;
        std::shared_ptr<const std::vector<std::pair<uint32_t, std::string>>> names;
    };
    struct View {
        ViewerSpec spec;
        std::vector<Watcher> viewers;
        uint64_t version = UINT64_MAX;  ///< of the last frame
        uint32_t samples = 0;           ///< in the last frame
        uint32_t launches = 0;          ///< at that version (guards against restarts)
        uint64_t failed_version = UINT64_MAX;
        Clock::time_point next_render{};
        std::shared_ptr<const ViewFrame> frame;            ///< the newest frame
        std::map<std::string, StreamChannel::Part> parts;  ///< it encoded, per highlight
    };
    /// The view render_one picked, copied out of the lock for the render.
    struct ViewPick {
        std::string key;
        ViewerSpec spec;
        uint64_t version = 0;                       ///< of the scene it shows
        std::set<std::string> highlights;           ///< of the view's viewers ("" for none)
        std::shared_ptr<const ViewFrame> previous;  ///< of this accumulation, with its ids
    };
    /// A viewer render made ready to hand out.
    struct RenderedFrame {
        std::shared_ptr<ViewFrame> frame;                  ///< tone-mapped; null if it failed
        std::map<std::string, StreamChannel::Part> parts;  ///< its JPEG, per highlight
        Status status;  ///< the render's error, or the first failed encoding's
    };

    /// `frame` as one stream part for viewers highlighting `highlight`.
    Result<StreamChannel::Part> encode_part(const ViewFrame& frame, const std::string& highlight,
                                            int quality);
    /// Encodes the newest frame for viewers that joined with a highlight it lacked; false when
    /// none waited.
    bool serve_joiners();

    void run();
    /// Wakes the hub's thread (a new stream, a commit event to send).
    void poke();
    /// Renders the most overdue view that needs a frame; false when none did.
    bool render_one(Clock::time_point now);
    /// Whether `view` needs a frame at scene `version`: the scene moved, or accumulation can
    /// still improve the frame (or one more launch must trace the ids a highlight needs).
    static bool wants_frame(const View& view, uint64_t version);
    /// Drops the views nobody watches, then picks the most overdue view due a frame (at the
    /// live scene's `version`, or at its own past version); none when none is due or API work
    /// waits (counted as a deferred render).
    std::optional<ViewPick> pick_view(uint64_t version, Clock::time_point now);
    /// `frame` tone-mapped, taking its ids; without ids of its own, those of `previous` when it
    /// is at the same version.
    static std::shared_ptr<ViewFrame> tone_map_frame(
        Frame& frame, float exposure, const std::shared_ptr<const ViewFrame>& previous);
    /// Tone-maps the render's frame once, then encodes one JPEG per highlight `pick` asks for.
    RenderedFrame encode_render(Result<Frame>& frame, float exposure, const ViewPick& pick);
    /// Records the render of view `key` at scene `version` and offers its parts to the view's
    /// viewers; a failed render is counted and not retried before the scene moves.
    void offer_render(const std::string& key, uint64_t version, Clock::time_point now,
                      const Result<Frame>& frame, RenderedFrame&& rendered);
    uint64_t scene_version() const;

    Engine& m_engine;
    std::function<bool()> m_api_busy;
    const std::size_t m_max_view_bytes;
    CancelToken m_cancel;  ///< the hub's renders; cancelled by stop()

    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    bool m_stopping = false;
    bool m_poked = false;
    std::map<std::string, View> m_views;
    CommitEvents m_events;
    StreamHubStats m_stats;
    std::thread m_thread;
};

}  // namespace strata::server

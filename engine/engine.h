#pragma once
// The engine facade: the scene, the acceleration graph and the launch state behind one
// thread-safe interface. It knows nothing of HTTP or JSON.
//
// Concurrency model
//   - The editable scene is guarded by a reader/writer lock: apply() writes, queries read.
//   - Commits and launches are serialised by a launch mutex. A commit takes the scene lock
//     exclusively while it plans, builds and copies shading data, then releases it.
//   - A render commits and then traces while holding only the launch mutex: edits keep landing
//     in the scene meanwhile, but tracing reads only the acceleration structures and the frame
//     state, which only a commit changes. Each render therefore sees exactly one version.
//   Lock order is always launch, then scene.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/accel/accel_graph.h"
#include "engine/counters.h"
#include "engine/render/frame.h"
#include "engine/render/frame_state.h"
#include "engine/render/pick.h"
#include "engine/render/primary.h"
#include "engine/render/render_request.h"
#include "engine/render/renderer.h"
#include "engine/scene/edit_history.h"

namespace strata {

namespace durable {
class Journal;
}

struct EngineConfig {
    AccelConfig accel;
    SceneBudget budget;  ///< checked when a batch is applied (a TooLarge error beyond)
    HistoryLimits history;  ///< the undo history's bounds (edit_history.h)
};

/// Result of an applied batch.
struct ApplyResult {
    uint64_t version = 0;
    std::size_t applied = 0;
};

/// What Engine::replace_with_snapshot() did.
struct SnapshotReplace {
    uint64_t old_version = 0;  ///< the scene it replaced
    uint64_t version = 0;      ///< the snapshot's, the scene's now
    double load_ms = 0.0;      ///< decoding and loading the new scene, outside every lock
    double lock_ms = 0.0;      ///< the exclusive hold: the journal's cut and the swap
};

class Engine {
public:
    static Result<std::unique_ptr<Engine>> create(const EngineConfig& config = {});
    /// The Embree device this engine shares with others (AccelConfig::shared_device), or null.
    const std::shared_ptr<SharedEmbree>& shared_device() const {
        return m_config.accel.shared_device;
    }

    /// Validates and applies a batch atomically; the version moves by one on success.
    Result<ApplyResult> apply(EditBatch&& batch);

    /// As apply(), but only when the scene is at `expected_version` (when given): the check and
    /// the apply happen under one lock, so no other batch can land in between. A mismatch is a
    /// VersionMismatch error and leaves the scene untouched.
    Result<ApplyResult> apply(EditBatch&& batch, std::optional<uint64_t> expected_version);

    /// The batch that undoes (redoes) the newest batch on the undo (redo) stack
    /// (edit_history.h), for the scene at `version`: apply it with that expected version. A
    /// NothingToUndo error when the stack is empty, VersionMismatch when the scene is elsewhere.
    Result<EditBatch> undo_batch(uint64_t version) const;
    Result<EditBatch> redo_batch(uint64_t version) const;
    /// A page of the history (EditHistory::page).
    HistoryPage history(std::size_t limit, uint64_t before) const;

    /// Checks `batch` against the scene at `version` without keeping it: every rule runs, then
    /// the changes are rolled back (no version bump, no journal record, nothing counted). A
    /// shared edit log (server/replica) validates a batch this way before appending it. The
    /// scene at another version is a VersionMismatch error.
    Status validate(EditBatch&& batch, uint64_t version);

    /// From now on every applied batch is written to `journal` (engine/durable/journal.h) under
    /// the scene lock before apply() returns, and apply() waits until it is as durable as the
    /// journal's fsync mode promises. A batch the journal cannot store is not applied (a Storage
    /// error). Call before serving; the journal must outlive the engine's use of it.
    void set_journal(durable::Journal* journal) { m_journal = journal; }
    durable::Journal* journal() const { return m_journal; }

    /// Recovery: loads a whole-scene batch into this empty engine and sets the version it had
    /// (a snapshot's). Not journaled.
    Status restore(EditBatch&& scene, uint64_t version);
    /// Recovery: loads a snapshot's scene (`payload`: its edit-batch bytes, edit_codec.h) into
    /// this empty engine edit by edit, straight into the scene's storage: no whole batch decoded
    /// first, no undo log. On error the engine is left empty.
    Status restore_snapshot(std::string_view payload, uint64_t version);
    /// Recovery, after restore_snapshot: the history the snapshot was written with (what undo
    /// and GET history reach), which the journal records replayed after it extend. Not
    /// journaled.
    void restore_history(HistoryState&& state);
    /// Replaces the whole scene, whatever it holds, with a snapshot's scene (`payload`, as for
    /// restore_snapshot) at `version`, which must be newer than the scene's: a replica that finds
    /// its log trimmed past its version jumps to the log's snapshot. The new scene and a fresh
    /// acceleration graph are built outside the locks, then `before_swap` runs (a data directory
    /// writes the snapshot there); the launch and scene locks are held only while the journal
    /// (when attached) starts a new segment at `version` and the scenes are swapped. Readers and
    /// launches see the old scene or the new one, never a mix; the next commit builds
    /// everything, as after a restore. On any error nothing changed. The caller must be the
    /// only writer meanwhile (the replica's reader is). With a journal attached, call it through
    /// DurableStore::replace_scene, which writes the snapshot the new segment starts from.
    Result<SnapshotReplace> replace_with_snapshot(
        std::string_view payload, uint64_t version,
        const std::function<Status()>& before_swap = nullptr);

    /// Brings the acceleration graph in line with the scene, doing the least work.
    Result<RebuildReport> commit();

    /// What commit() would do now, without doing it.
    RebuildReport plan() const;

    /// Commits, renders and encodes one frame (PNG or EXR, see frame_encode.h). Encoding runs
    /// after the launch, so it does not hold up other launches.
    Result<EncodedFrame> render(const RenderRequest& request);

    /// Commits and renders one frame's linear buffers: what render() encodes.
    Result<Frame> render_frame(const RenderRequest& request);

    /// Commits once and renders each of `bands` of `request` (RenderRequest::band), all from
    /// that one commit: the frames show one version. The request's own band is ignored.
    Result<std::vector<Frame>> render_bands(const RenderRequest& request,
                                            const std::vector<RowBand>& bands);

    /// Commits, then traces one primary ray per pixel (primary.h) into `out`, whose buffers are
    /// reused when they already have the frame's size (no allocation, no page faults: for callers
    /// that trace many frames).
    Status render_primary(const PrimarySettings& settings, Frame& out);
    /// The same into a new Frame.
    Result<Frame> render_primary(const PrimarySettings& settings);

    /// Commits, then traces one ray through each pixel of `request` (pick.h).
    Result<PickResult> pick(const PickRequest& request);

    /// Runs `f(const FrameState&, const TlasStrategy&, const RebuildReport&)` after a commit, with
    /// launches serialised: the hook the renderer uses to trace one consistent version. When `f`
    /// itself returns a Result, that Result is the answer (a commit error and `f`'s error come
    /// back the same way, never nested).
    template <class F>
    auto launch(F&& f) {
        return launch_at(std::nullopt, std::forward<F>(f));
    }
    /// The same with the animated instances shown at scene time `time` (RenderRequest::time).
    template <class F>
    auto launch_at(std::optional<float> time, F&& f) {
        using R = decltype(f(std::declval<const FrameState&>(), std::declval<const TlasStrategy&>(),
                             std::declval<const RebuildReport&>()));
        using Out = std::conditional_t<is_expected_v<R>, R, Result<R>>;
        std::lock_guard launch_lock(m_launch_mutex);
        auto report = commit_locked(nullptr, time);
        if (!report) return Out(Unexpected(std::move(report).error()));
        Out result = f(m_frame, m_accel->tlas(), report.value());
        if (Status s = m_accel->device_status("tracing"); !s) return Out(Unexpected(s.error()));
        return result;
    }

    /// The scene's version, as the last apply, restore or replace left it. Takes no lock, so a
    /// thread that must never wait for a long batch (the front end's event loop) can poll it.
    uint64_t version() const { return m_version.load(std::memory_order_acquire); }

    /// Runs `f(const Scene&)` under the scene's read lock.
    template <class F>
    auto read(F&& f) const {
        std::shared_lock lock(m_scene_mutex);
        return f(m_scene);
    }
    /// The same, with the history of the same version.
    template <class F>
    auto read_with_history(F&& f) const {
        std::shared_lock lock(m_scene_mutex);
        return f(m_scene, m_history);
    }

    /// Cumulative counters.
    EngineCounters counters() const;
    /// The compacted BLASes (BuildOptions::compact) as the most recent commit left them.
    CompactionSummary compaction() const;
    /// The report of the most recent commit (default-constructed before the first).
    RebuildReport last_report() const;
    /// Called with every commit's report, on the committing thread, right after the counters
    /// took it (one listener; an empty function removes it, and once this returns the old one is
    /// not running and never runs again). The commit may still hold the scene for its launch:
    /// the listener must be quick and must not call into this engine.
    using CommitListener = std::function<void(const RebuildReport&)>;
    void set_commit_listener(CommitListener listener);
    /// Acceleration-structure memory now (takes no lock a launch or an edit holds).
    int64_t memory_bytes(MemoryCategory c) const;

    void set_refit_policy(const RefitPolicy& p);
    RefitPolicy refit_policy() const;

    /// Waits until background acceleration work (a TLAS merge) has finished building; the next
    /// commit swaps it in. For tests and benchmarks that need a known state.
    void wait_for_background();

    /// Counts rays a launch traced (called by renderers).
    void add_rays(uint64_t rays, double seconds);

private:
    Engine(const EngineConfig& config, std::unique_ptr<AccelGraph> accel)
        : m_config(config), m_accel(std::move(accel)), m_history(config.history) {}
    /// The commit, with the launch mutex held. With `keep_scene_lock`, the scene's exclusive
    /// lock is handed to the caller instead of released (the caller then reads the scene at
    /// exactly the committed version). With `time`, the animated instances show that scene time
    /// instead of the scene's.
    Result<RebuildReport> commit_locked(
        std::unique_lock<std::shared_mutex>* keep_scene_lock = nullptr,
        std::optional<float> time = std::nullopt);

    const EngineConfig m_config;  ///< what a replaced scene's budget and acceleration graph use
    mutable std::mutex m_launch_mutex;
    mutable std::shared_mutex m_scene_mutex;
    Scene m_scene;
    std::atomic<uint64_t> m_version{0};  ///< m_scene's version, stored under m_scene_mutex
    /// Publishes m_scene's version to version(); called with m_scene_mutex held exclusively.
    void publish_version() { m_version.store(m_scene.version(), std::memory_order_release); }
    /// Replaced only by replace_with_snapshot(), under the launch, scene and accel locks.
    std::unique_ptr<AccelGraph> m_accel;
    mutable std::mutex m_accel_mutex;  ///< lets memory_bytes() read m_accel during a replace
    durable::Journal* m_journal = nullptr;
    EditHistory m_history;  ///< guarded by m_scene_mutex, like the scene whose versions it lists
    FrameState m_frame;
    Renderer m_renderer;  ///< guarded by the launch mutex (it holds the accumulation state)

    mutable std::mutex m_stats_mutex;
    EngineCounters m_counters;
    RebuildReport m_last_report;
    CompactionSummary m_compaction;  ///< guarded by m_stats_mutex
    /// The store and version m_compaction was read from (the launch mutex guards these).
    const BlasStore* m_compaction_of = nullptr;
    uint64_t m_compaction_version = 0;
    CommitListener m_commit_listener;  ///< guarded by m_stats_mutex
};

}  // namespace strata

#include "engine/engine.h"

#include "engine/core/memory_trim.h"
#include "engine/core/timer.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal.h"
#include "engine/image/texture_decode.h"
#include "engine/render/frame_encode.h"

namespace strata {

Result<std::unique_ptr<Engine>> Engine::create(const EngineConfig& config) {
    auto accel = AccelGraph::create(config.accel);
    if (!accel) return Unexpected(accel.error());
    auto engine = std::unique_ptr<Engine>(new Engine(config, std::move(accel.value())));
    engine->m_scene.set_budget(config.budget);
    return engine;
}

namespace {

/// Whether applying the batch frees mesh arrays (then the heap is worth trimming).
bool releases_mesh_data(const EditBatch& batch) {
    for (const Edit& e : batch.edits) {
        if (std::holds_alternative<RemoveMesh>(e) || std::holds_alternative<Clear>(e) ||
            std::holds_alternative<ReplaceMeshTopology>(e))
            return true;
    }
    return false;
}

/// Decodes the batch's textures before the scene lock is taken, so that a large image holds up
/// no read; the decodes of one batch stay within the texture budget together. An image over the
/// budget is left to the rule, which refuses it from its header with the exact room left.
void decode_textures_ahead(EditBatch& batch, uint64_t budget) {
    uint64_t left = budget;
    for (Edit& edit : batch.edits) {
        auto* e = std::get_if<AddTexture>(&edit);
        if (!e || e->decoded) continue;
        TextureLimits limits;
        limits.max_bytes = left;
        Result<TextureImage> image = decode_texture(e->data, limits, e->color_space);
        if (!image && image.error().code == ErrorCode::TooLarge) continue;
        if (image) left -= std::min(left, image->bytes());
        e->decoded = std::make_shared<DecodedTexture>(DecodedTexture{std::move(image)});
    }
}

}  // namespace

Result<ApplyResult> Engine::apply(EditBatch&& batch) {
    return apply(std::move(batch), std::nullopt);
}

Result<ApplyResult> Engine::apply(EditBatch&& batch, std::optional<uint64_t> expected_version) {
    const std::size_t count = batch.edits.size();
    if (batch.info.time_ms == 0) batch.info.time_ms = unix_ms();
    const BatchInfo info = batch.info;
    auto ops = count_ops(batch);
    decode_textures_ahead(batch, m_config.budget.max_texture_bytes);
    const bool frees_meshes = releases_mesh_data(batch);
    // The record is encoded before the apply moves the arrays out, and outside the lock.
    std::optional<durable::PendingRecord> record;
    if (m_journal) record = durable::prepare_record(batch);
    uint64_t journal_position = 0;
    Result<uint64_t> version = [&]() -> Result<uint64_t> {
        std::unique_lock lock(m_scene_mutex);
        if (expected_version && *expected_version != m_scene.version())
            return failure(ErrorCode::VersionMismatch,
                           "the scene is at version " + std::to_string(m_scene.version()) +
                               ", not " + std::to_string(*expected_version));
        const auto journal = [&](uint64_t next) -> Status {
            auto position = m_journal->append(*record, next);
            if (!position) return Unexpected(position.error());
            journal_position = position.value();
            return {};
        };
        EditBatch inverse;
        Result<uint64_t> applied = m_scene.apply(
            std::move(batch), m_journal ? std::function<Status(uint64_t)>(journal) : nullptr,
            m_config.history.max_undo ? &inverse : nullptr);
        if (applied) m_history.record(applied.value(), info, std::move(ops), std::move(inverse));
        publish_version();
        return applied;
    }();
    // Group commit: the fsync happens here, outside the scene lock.
    if (version && m_journal) {
        if (Status s = m_journal->wait_durable(journal_position); !s)
            version = Unexpected(s.error());
    }
    {
        std::lock_guard stats(m_stats_mutex);
        if (!version) {
            ++m_counters.batches_rejected;
            return Unexpected(version.error());
        }
        ++m_counters.batches_applied;
        m_counters.edits_applied += count;
    }
    if (frees_meshes) release_free_memory();
    return ApplyResult{version.value(), count};
}

namespace {

/// The undo (redo) batch of `history` for a scene at `scene_version`, asked for at `version`.
Result<EditBatch> history_batch(const EditHistory& history, bool redo, uint64_t scene_version,
                                uint64_t version) {
    if (version != scene_version)
        return failure(ErrorCode::VersionMismatch, "the scene is at version " +
                                                       std::to_string(scene_version) + ", not " +
                                                       std::to_string(version));
    if (auto batch = redo ? history.redo_batch() : history.undo_batch()) return std::move(*batch);
    return failure(ErrorCode::NothingToUndo,
                   redo ? "nothing to redo: no undo since the last edit"
                        : "nothing to undo: no batch since the start, the newest snapshot or the "
                          "history's limits is left to take back");
}

}  // namespace

Result<EditBatch> Engine::undo_batch(uint64_t version) const {
    std::shared_lock lock(m_scene_mutex);
    return history_batch(m_history, false, m_scene.version(), version);
}

Result<EditBatch> Engine::redo_batch(uint64_t version) const {
    std::shared_lock lock(m_scene_mutex);
    return history_batch(m_history, true, m_scene.version(), version);
}

HistoryPage Engine::history(std::size_t limit, uint64_t before) const {
    std::shared_lock lock(m_scene_mutex);
    return m_history.page(limit, before);
}

Status Engine::validate(EditBatch&& batch, uint64_t version) {
    decode_textures_ahead(batch, m_config.budget.max_texture_bytes);
    std::unique_lock lock(m_scene_mutex);
    if (version != m_scene.version())
        return failure(ErrorCode::VersionMismatch,
                       "the scene is at version " + std::to_string(m_scene.version()) + ", not " +
                           std::to_string(version));
    // The hook runs once every rule has passed; its error makes the scene roll the batch back.
    bool passed = false;
    auto checked = m_scene.apply(std::move(batch), [&](uint64_t) -> Status {
        passed = true;
        return failure(ErrorCode::Internal, "validation only");
    });
    if (passed) return {};
    return Unexpected(std::move(checked).error());
}

Status Engine::restore(EditBatch&& scene, uint64_t version) {
    std::unique_lock lock(m_scene_mutex);
    if (m_scene.version() != 0)
        return failure(ErrorCode::Internal, "restore needs an empty engine");
    auto applied = m_scene.apply(std::move(scene));
    if (!applied) return Unexpected(applied.error());
    m_scene.restore_version(version);
    publish_version();
    return {};
}

namespace {

/// Loads a snapshot's payload into `scene` (empty), edit by edit; on error it is left part-built.
Status load_snapshot(Scene& scene, std::string_view payload, uint64_t version) {
    Status s = durable::decode_each(payload, [&](Edit&& e) { return scene.load(std::move(e)); });
    if (s) s = scene.finish_load(version);
    return s;
}

}  // namespace

Status Engine::restore_snapshot(std::string_view payload, uint64_t version) {
    std::unique_lock lock(m_scene_mutex);
    if (m_scene.version() != 0 || m_scene.instances().size() || m_scene.meshes().size())
        return failure(ErrorCode::Internal, "restore needs an empty engine");
    Status s = load_snapshot(m_scene, payload, version);
    if (!s) m_scene.reset();
    publish_version();
    return s;
}

void Engine::restore_history(HistoryState&& state) {
    std::unique_lock lock(m_scene_mutex);
    m_history.restore(std::move(state));
}

Result<SnapshotReplace> Engine::replace_with_snapshot(std::string_view payload, uint64_t version,
                                                      const std::function<Status()>& before_swap) {
    Stopwatch clock;
    SnapshotReplace out;
    out.version = version;
    auto not_newer = [&](uint64_t current) {
        return failure(ErrorCode::VersionMismatch,
                       "the snapshot of version " + std::to_string(version) +
                           " is not newer than the scene (version " + std::to_string(current) +
                           "): nothing replaced");
    };
    if (const uint64_t current = read([](const Scene& s) { return s.version(); });
        version <= current)
        return not_newer(current);

    // Step: the new scene and an empty acceleration graph, built while the old scene serves. A
    // loaded scene lists everything as added, so the fresh graph's first commit builds it all,
    // exactly as in an engine that restored the snapshot; nothing of the old graph (slots, BLASes,
    // TLAS tiers, background merges) carries over.
    Scene fresh;
    fresh.set_budget(m_config.budget);
    if (Status s = load_snapshot(fresh, payload, version); !s) return Unexpected(s.error());
    auto accel = AccelGraph::create(m_config.accel);
    if (!accel) return Unexpected(accel.error());
    out.load_ms = clock.ms();
    if (before_swap) {
        if (Status s = before_swap(); !s) return Unexpected(s.error());
    }

    // Step: the swap. The old scene, graph and frame state are destroyed after the locks go.
    std::unique_ptr<AccelGraph> graph = std::move(accel.value());
    FrameState frame;
    {
        std::lock_guard launch_lock(m_launch_mutex);
        std::unique_lock lock(m_scene_mutex);
        Stopwatch held;
        out.old_version = m_scene.version();
        if (version <= out.old_version) return not_newer(out.old_version);
        // Later records go to a segment that starts at the snapshot's version (recovery then
        // reads the snapshot and that segment, never the old scene's records followed by a gap).
        if (m_journal) {
            if (Status s = m_journal->rotate(version); !s) return Unexpected(s.error());
        }
        graph->set_refit_policy(m_accel->refit_policy());
        std::swap(m_scene, fresh);
        m_history.clear();
        publish_version();
        {
            std::lock_guard accel_lock(m_accel_mutex);
            std::swap(m_accel, graph);
        }
        m_compaction_of = nullptr;  // the next commit reads the new graph's list
        {
            std::lock_guard stats(m_stats_mutex);
            m_compaction = {};
        }
        std::swap(m_frame, frame);
        out.lock_ms = held.ms();
    }
    fresh = Scene();
    graph.reset();
    frame = FrameState();
    release_free_memory();
    return out;
}

Result<RebuildReport> Engine::commit() {
    std::lock_guard launch_lock(m_launch_mutex);
    return commit_locked();
}

Result<RebuildReport> Engine::commit_locked(std::unique_lock<std::shared_mutex>* keep_scene_lock,
                                            std::optional<float> time) {
    Stopwatch clock;
    std::unique_lock lock(m_scene_mutex);
    Timeline shown = m_scene.timeline();
    if (time) shown.time = *time;
    m_scene.show(shown);  // marks the animated instances that move
    m_frame.clock = shown;
    RebuildReport report;
    int64_t freed = 0;  // acceleration-structure bytes the commit released
    if (m_scene.changes().empty()) {
        // Nothing changed: no planning, no Embree call. The flattenings since the last commit
        // may still have evaluated world transforms that moved nothing (an animation holding a
        // key): this report counts them, and the next does not.
        report.version = m_scene.version();
        report.world_transforms = m_scene.changes().world_transforms();
        m_scene.clear_changes();
        report.tlas_instances = m_accel->tlas().instance_count();
        // No scene change, but a background TLAS merge that finished is swapped in now.
        m_accel->maintain(report);
        report.memory_blas_bytes = m_accel->memory_bytes(MemoryCategory::Blas);
        report.memory_tlas_bytes = m_accel->memory_bytes(MemoryCategory::Tlas);
    } else {
        const int64_t held_before = m_accel->memory_bytes(MemoryCategory::Blas) +
                                    m_accel->memory_bytes(MemoryCategory::Tlas);
        auto executed = m_accel->execute(m_scene, m_accel->plan(m_scene));
        if (!executed) return Unexpected(executed.error());
        report = std::move(executed.value());
        Stopwatch sync_clock;
        m_frame.sync(m_scene);
        report.phases.sync_ms = sync_clock.ms();
        m_scene.clear_changes();
        freed = held_before - report.memory_blas_bytes - report.memory_tlas_bytes;
    }
    if (keep_scene_lock) {
        *keep_scene_lock = std::move(lock);
    } else {
        lock.unlock();
        if (freed >= int64_t(TRIM_THRESHOLD_BYTES)) release_free_memory();
    }
    report.phases.total_ms = clock.ms();
    // The compacted BLASes change only when one is built, refit or freed: their list is walked
    // then, and read (GET /v1/stats) from the copy.
    const BlasStore& blas = m_accel->blas();
    std::optional<CompactionSummary> compaction;
    if (&blas != m_compaction_of || blas.compaction_version() != m_compaction_version) {
        compaction = blas.compaction();
        m_compaction_of = &blas;
        m_compaction_version = blas.compaction_version();
    }

    std::lock_guard stats(m_stats_mutex);
    if (compaction) m_compaction = std::move(*compaction);
    report.compaction = m_compaction.totals;
    EngineCounters& c = m_counters;
    ++c.commits;
    if (report.no_accel_work()) ++c.noop_commits;
    c.blas_rebuilds += report.blas_rebuilds;
    c.blas_refits += report.blas_refits;
    c.tlas_updates += report.tlas_action == TlasAction::Update;
    c.tlas_rebuilds += report.tlas_action == TlasAction::Rebuild;
    c.primitives_built += report.primitives_built;
    c.primitives_refit += report.primitives_refit;
    c.clusters_rebuilt += report.clusters_rebuilt;
    c.clusters_refit += report.clusters_refit;
    c.world_transforms += report.world_transforms;
    c.tlas_static_rebuilds += report.tlas.static_rebuild[0] != '\0';
    c.tlas_merges += report.tlas.merge_swapped;
    c.tlas_merge_seconds += report.tlas.merge_swapped ? report.tlas.merge_build_ms / 1000.0 : 0.0;
    c.tlas_merges_cancelled += report.tlas.merge_cancelled;
    c.commit_seconds += report.phases.total_ms / 1000.0;
    m_last_report = report;
    if (m_commit_listener) m_commit_listener(report);
    return report;
}

void Engine::set_commit_listener(CommitListener listener) {
    std::lock_guard stats(m_stats_mutex);
    m_commit_listener = std::move(listener);
}

RebuildReport Engine::plan() const {
    std::lock_guard launch_lock(m_launch_mutex);
    std::shared_lock lock(m_scene_mutex);
    return m_accel->plan(m_scene).report;
}

Result<Frame> Engine::render_primary(const PrimarySettings& settings) {
    Frame out;
    if (Status s = render_primary(settings, out); !s) return Unexpected(s.error());
    return out;
}

Status Engine::render_primary(const PrimarySettings& settings, Frame& out) {
    Stopwatch clock;
    auto launched =
        launch([&](const FrameState& state, const TlasStrategy& tlas, const RebuildReport& report) {
            strata::render_primary(tlas, state, settings, out.buffers);
            out.info = FrameInfo{state.version, report, 1, 1, out.buffers.pixel_count(), 0.0};
            return true;
        });
    if (!launched) return Unexpected(launched.error());
    out.info.render_ms = clock.ms();
    add_rays(out.info.rays, out.info.render_ms / 1000.0);
    return {};
}

Result<Frame> Engine::render_frame(const RenderRequest& request) {
    if (Status s = check_render_request(request); !s) return Unexpected(s.error());
    auto frame = launch_at(request.time, [&](const FrameState& state, const TlasStrategy& tlas,
                                             const RebuildReport& report) -> Result<Frame> {
        auto rendered = m_renderer.render(tlas, state, request);
        if (rendered) rendered->info.report = report;
        return rendered;
    });
    if (frame) add_rays(frame->info.rays, frame->info.render_ms / 1000.0);
    return frame;
}

Result<std::vector<Frame>> Engine::render_bands(const RenderRequest& request,
                                                const std::vector<RowBand>& bands) {
    RenderRequest band = request;
    for (const RowBand& b : bands) {
        band.band = b;
        if (Status s = check_render_request(band); !s) return Unexpected(s.error());
    }
    auto frames = launch_at(request.time, [&](const FrameState& state, const TlasStrategy& tlas,
                                              const RebuildReport& report)
                                              -> Result<std::vector<Frame>> {
        std::vector<Frame> out;
        for (const RowBand& b : bands) {
            band.band = b;
            auto rendered = m_renderer.render(tlas, state, band);
            if (!rendered) return Unexpected(rendered.error());
            rendered->info.report = report;
            out.push_back(std::move(rendered.value()));
        }
        return out;
    });
    if (frames) {
        // One render in the counters, however many bands it traced.
        uint64_t rays = 0;
        double ms = 0.0;
        for (const Frame& f : frames.value()) {
            rays += f.info.rays;
            ms += f.info.render_ms;
        }
        add_rays(rays, ms / 1000.0);
    }
    return frames;
}

Result<EncodedFrame> Engine::render(const RenderRequest& request) {
    auto frame = render_frame(request);
    if (!frame) return Unexpected(frame.error());
    auto encoded = encode_frame(frame->buffers, request, exr_attributes(frame.value()));
    if (encoded) encoded->info = std::move(frame->info);
    return encoded;
}

Result<PickResult> Engine::pick(const PickRequest& request) {
    if (Status s = check_pick_request(request); !s) return Unexpected(s.error());
    std::lock_guard launch_lock(m_launch_mutex);
    // The scene stays locked from the commit to the end of the pick, so the ids the hits are
    // named with are those of the version the rays saw (edits wait for a few rays).
    std::unique_lock<std::shared_mutex> scene_lock;
    auto report = commit_locked(&scene_lock, request.time);
    if (!report) return Unexpected(report.error());
    const auto camera = resolve_camera(request.camera, m_frame.camera);
    if (!camera) return Unexpected(camera.error());
    PickResult result;
    result.version = m_frame.version;
    result.hits = pick_pixels(m_accel->tlas(), m_frame, m_scene, camera.value(), request);
    if (Status s = m_accel->device_status("picking"); !s) return Unexpected(s.error());
    scene_lock.unlock();
    std::lock_guard stats(m_stats_mutex);
    ++m_counters.picks;
    m_counters.rays_traced += request.pixels.size();
    return result;
}

void Engine::wait_for_background() {
    std::lock_guard launch_lock(m_launch_mutex);
    m_accel->wait_for_background();
}

void Engine::add_rays(uint64_t rays, double seconds) {
    std::lock_guard stats(m_stats_mutex);
    ++m_counters.renders;
    m_counters.rays_traced += rays;
    m_counters.render_seconds += seconds;
}

EngineCounters Engine::counters() const {
    std::lock_guard stats(m_stats_mutex);
    return m_counters;
}

int64_t Engine::memory_bytes(MemoryCategory c) const {
    std::lock_guard accel_lock(m_accel_mutex);
    return m_accel->memory_bytes(c);
}

CompactionSummary Engine::compaction() const {
    std::lock_guard stats(m_stats_mutex);
    return m_compaction;
}

RebuildReport Engine::last_report() const {
    std::lock_guard stats(m_stats_mutex);
    return m_last_report;
}

void Engine::set_refit_policy(const RefitPolicy& p) {
    std::lock_guard launch_lock(m_launch_mutex);
    m_accel->set_refit_policy(p);
}

RefitPolicy Engine::refit_policy() const {
    std::lock_guard launch_lock(m_launch_mutex);
    return m_accel->refit_policy();
}

}  // namespace strata

#include "engine/engine.h"

#include "engine/core/timer.h"
#include "engine/render/frame_encode.h"

namespace strata {

Result<std::unique_ptr<Engine>> Engine::create(const EngineConfig& config) {
    auto accel = AccelGraph::create(config.accel);
    if (!accel) return accel.error();
    return std::unique_ptr<Engine>(new Engine(std::move(accel.value())));
}

Result<ApplyResult> Engine::apply(EditBatch&& batch) { return apply(std::move(batch), std::nullopt); }

Result<ApplyResult> Engine::apply(EditBatch&& batch, std::optional<uint64_t> expected_version) {
    const std::size_t count = batch.edits.size();
    Result<uint64_t> version = [&]() -> Result<uint64_t> {
        std::unique_lock lock(m_scene_mutex);
        if (expected_version && *expected_version != m_scene.version())
            return make_error(ErrorCode::VersionMismatch,
                              "the scene is at version " + std::to_string(m_scene.version()) +
                                  ", not " + std::to_string(*expected_version));
        return m_scene.apply(std::move(batch));
    }();
    std::lock_guard stats(m_stats_mutex);
    if (!version) {
        ++m_counters.batches_rejected;
        return version.error();
    }
    ++m_counters.batches_applied;
    m_counters.edits_applied += count;
    return ApplyResult{version.value(), count};
}

Result<RebuildReport> Engine::commit() {
    std::lock_guard launch_lock(m_launch_mutex);
    return commit_locked();
}

Result<RebuildReport> Engine::commit_locked() {
    Stopwatch clock;
    std::unique_lock lock(m_scene_mutex);
    RebuildReport report;
    if (m_scene.changes().empty()) {
        // Nothing changed: no planning, no Embree call.
        report.version = m_scene.version();
        report.tlas_instances = m_accel->tlas().instance_count();
        report.memory_blas_bytes = m_accel->memory_bytes(MemoryCategory::Blas);
        report.memory_tlas_bytes = m_accel->memory_bytes(MemoryCategory::Tlas);
    } else {
        auto executed = m_accel->execute(m_scene, m_accel->plan(m_scene));
        if (!executed) return executed.error();
        report = std::move(executed.value());
        Stopwatch sync_clock;
        m_frame.sync(m_scene);
        report.phases.sync_ms = sync_clock.ms();
        m_scene.clear_changes();
    }
    lock.unlock();
    report.phases.total_ms = clock.ms();

    std::lock_guard stats(m_stats_mutex);
    EngineCounters& c = m_counters;
    ++c.commits;
    if (report.no_accel_work()) ++c.noop_commits;
    c.blas_rebuilds += report.blas_rebuilds;
    c.blas_refits += report.blas_refits;
    c.tlas_updates += report.tlas_action == TlasAction::Update;
    c.tlas_rebuilds += report.tlas_action == TlasAction::Rebuild;
    c.primitives_built += report.primitives_built;
    c.primitives_refit += report.primitives_refit;
    c.commit_seconds += report.phases.total_ms / 1000.0;
    m_last_report = report;
    return report;
}

RebuildReport Engine::plan() const {
    std::lock_guard launch_lock(m_launch_mutex);
    std::shared_lock lock(m_scene_mutex);
    return m_accel->plan(m_scene).report;
}

Result<PrimaryFrame> Engine::render_primary(const PrimarySettings& settings) {
    PrimaryFrame out;
    if (Status s = render_primary(settings, out); !s) return s.error();
    return out;
}

Status Engine::render_primary(const PrimarySettings& settings, PrimaryFrame& out) {
    Stopwatch clock;
    auto launched = launch([&](const FrameState& state, const TlasStrategy& tlas,
                               const RebuildReport& report) {
        strata::render_primary(tlas, state, settings, out.hits);
        out.report = report;
        out.version = state.version;
        return true;
    });
    if (!launched) return launched.error();
    add_rays(out.hits.pixel_count(), clock.ms() / 1000.0);
    return {};
}

Result<RenderedFrame> Engine::render_frame(const RenderRequest& request) {
    if (Status s = check_render_request(request); !s) return s.error();
    auto frame = launch([&](const FrameState& state, const TlasStrategy& tlas,
                            const RebuildReport& report) -> Result<RenderedFrame> {
        auto rendered = m_renderer.render(tlas, state, request);
        if (rendered) rendered.value().report = report;
        return rendered;
    });
    if (!frame) return frame.error();
    if (!frame.value()) return frame.value().error();
    add_rays(frame.value().value().rays, frame.value().value().render_ms / 1000.0);
    return std::move(frame.value().value());
}

Result<RenderedImage> Engine::render(const RenderRequest& request) {
    auto frame = render_frame(request);
    if (!frame) return frame.error();
    Stopwatch encode_clock;
    auto encoded = encode_frame(frame.value().buffers, request);
    if (!encoded) return encoded.error();
    RenderedImage image;
    image.bytes = std::move(encoded.value().bytes);
    image.content_type = std::move(encoded.value().content_type);
    image.version = frame.value().version;
    image.report = std::move(frame.value().report);
    image.samples = frame.value().samples;
    image.rays = frame.value().rays;
    image.render_ms = frame.value().render_ms;
    image.encode_ms = encode_clock.ms();
    return image;
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

// Past versions of the scene for at_version reads and renders (past_scenes.h).

#include "server/past_scenes.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "engine/durable/durable_store.h"
#include "engine/durable/past_version.h"
#include "server/server_config.h"

namespace strata::server {

SceneBudget scene_budget(const ServerConfig& c) {
    return {c.max_scene_triangles, c.max_scene_vertices, c.max_texture_mb << 20,
            c.max_scene_instances};
}

protocol::ApiLimits api_limits(const ServerConfig& c) {
    protocol::ApiLimits limits{
        protocol::JsonLimits{c.max_json_depth, c.max_array_elements, c.max_json_values},
        c.max_pixels, c.render_timeout_s, scene_budget(c), c.max_batch_edits};
    limits.import_sandbox.memory_mb = c.import_memory_mb;
    limits.import_sandbox.cpu_seconds = uint32_t(c.import_timeout_s);
    limits.import_sandbox.deadline_ms = uint32_t(c.import_timeout_s) * 1000;
    return limits;
}

EngineConfig engine_config(const ServerConfig& c) {
    EngineConfig config;
    config.budget = scene_budget(c);
    config.history.max_undo = c.undo_depth;
    config.history.max_bytes = c.undo_mb << 20;
    config.accel.tlas = *parse_tlas_kind(c.tlas);  // checked by the command line's parser
    config.accel.tlas_policy.max_dynamic_fraction = c.tlas_max_dynamic_fraction;
    config.accel.tlas_policy.min_instances = c.tlas_min_instances;
    config.accel.tlas_policy.background_merge = c.tlas_background_merge;
    config.accel.tlas_policy.array_min_instances = c.tlas_array_min_instances;
    return config;
}

Status PastScenes::check(const Engine& live, const durable::DurableStore* store,
                         uint64_t version) {
    const uint64_t now = live.version();
    if (version > now)
        return failure(ErrorCode::OutOfRange, "version " + std::to_string(version) +
                                                  " does not exist yet (the scene is at " +
                                                  std::to_string(now) + ")");
    if (!store)
        return failure(ErrorCode::InvalidArgument,
                       "past versions are read from the data directory: this server runs "
                       "without --data");
    return {};
}

Result<std::shared_ptr<Engine>> PastScenes::at(Engine& live, durable::DurableStore* store,
                                               uint64_t version) {
    if (version == live.version()) return std::shared_ptr<Engine>(&live, [](Engine*) {});
    if (Status s = check(live, store, version); !s) return Unexpected(s.error());
    std::lock_guard lock(m_mutex);
    return load(*store, version);
}

Result<std::shared_ptr<Engine>> PastScenes::for_stream(Engine& live, durable::DurableStore* store,
                                                       uint64_t version) {
    if (Status s = check(live, store, version); !s) return Unexpected(s.error());
    std::lock_guard lock(m_mutex);
    m_streamed.erase(std::remove_if(m_streamed.begin(), m_streamed.end(),
                                    [](const Streamed& s) { return s.second.expired(); }),
                     m_streamed.end());
    for (const auto& [v, engine] : m_streamed) {
        if (auto held = engine.lock(); held && v == version) return held;
    }
    if (m_streamed.size() >= m_max_streamed) {
        std::string held;
        for (const auto& [v, engine] : m_streamed)
            held += (held.empty() ? "" : ", ") + std::to_string(v);
        return failure(ErrorCode::TooLarge,
                       "open streams hold " + std::to_string(m_streamed.size()) +
                           " past versions already (" + held +
                           "), the most they may: watch one of those, or the live scene");
    }
    auto engine = load(*store, version);
    if (engine) m_streamed.emplace_back(version, engine.value());
    return engine;
}

Result<std::shared_ptr<Engine>> PastScenes::load(durable::DurableStore& store, uint64_t version) {
    for (auto it = m_loaded.begin(); it != m_loaded.end(); ++it) {
        if (it->first != version) continue;
        Loaded found = std::move(*it);
        m_loaded.erase(it);
        m_loaded.push_back(found);
        return found.second;
    }
    std::shared_ptr<Engine> shared;
    for (const auto& [v, engine] : m_streamed) {
        if (v == version) shared = engine.lock();
    }
    if (!shared) {
        durable::PastVersionLoad load;
        auto engine = durable::load_past_version(store.directory(), version, m_config, &load);
        if (!engine) return Unexpected(engine.error());
        spdlog::info(
            "loaded version {} for at_version reads: snapshot {}, {} records replayed from "
            "{} journal bytes in {:.1f} ms",
            version, load.snapshot_version, load.records_replayed, load.journal_bytes,
            load.load_ms);
        shared = std::move(engine.value());
    }
    m_loaded.emplace_back(version, shared);
    while (m_loaded.size() > m_keep) m_loaded.pop_front();
    return shared;
}

}  // namespace strata::server

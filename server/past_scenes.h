#pragma once
// Older versions of the scene for reads and renders with `at_version=N`: loaded from the data
// directory beside the live scene (engine/durable/past_version.h), the last few kept loaded so
// that several frames or reads of one version pay the load once. A frame stream at a version
// holds that version's engine while it is open; streams of one version share it, and a bounded
// number of versions may be held by streams at once.

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "engine/engine.h"
#include "protocol/api.h"

namespace strata::durable {
class DurableStore;
}

namespace strata::server {

struct ServerConfig;

/// The engine configuration of `c`: the scene budget, undo bounds and TLAS strategy.
EngineConfig engine_config(const ServerConfig& c);
/// The scene budget the flags set (--max-scene-triangles, ...).
SceneBudget scene_budget(const ServerConfig& c);
/// The request limits the flags set (--max-json-depth, --max-pixels, ...).
protocol::ApiLimits api_limits(const ServerConfig& c);

class PastScenes {
public:
    /// Past scenes are made with `config`; at most `keep` are held for reads, and at most
    /// `max_streamed` more by open streams.
    explicit PastScenes(EngineConfig config, std::size_t keep = 2, std::size_t max_streamed = 4)
        : m_config(std::move(config)), m_keep(keep), m_max_streamed(max_streamed) {}

    /// The engine at `version`: `live` itself at its own version; an older version loaded from
    /// `store` (or found loaded). NotFound-like errors say why not: OutOfRange for a version the
    /// directory does not hold (or that does not exist yet), InvalidArgument without a data
    /// directory.
    Result<std::shared_ptr<Engine>> at(Engine& live, durable::DurableStore* store,
                                       uint64_t version);
    /// The engine at `version` for a frame stream, which holds it while it is open: as at(),
    /// but loaded from `store` at the live version too (the stream stays at that version as the
    /// scene moves on). TooLarge when streams hold `max_streamed` other versions already.
    Result<std::shared_ptr<Engine>> for_stream(Engine& live, durable::DurableStore* store,
                                               uint64_t version);

private:
    /// OutOfRange for a version after the live one, InvalidArgument without `store`.
    static Status check(const Engine& live, const durable::DurableStore* store,
                        uint64_t version);
    /// The engine at `version`, found loaded or loaded now (under m_mutex).
    Result<std::shared_ptr<Engine>> load(durable::DurableStore& store, uint64_t version);

    using Loaded = std::pair<uint64_t, std::shared_ptr<Engine>>;
    using Streamed = std::pair<uint64_t, std::weak_ptr<Engine>>;

    EngineConfig m_config;
    std::size_t m_keep;
    std::size_t m_max_streamed;
    std::mutex m_mutex;  ///< held while loading: one load at a time, none twice
    std::deque<Loaded> m_loaded;      ///< newest use last
    std::vector<Streamed> m_streamed;  ///< the versions open streams hold
};

}  // namespace strata::server

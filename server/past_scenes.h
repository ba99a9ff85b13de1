#pragma once
// Older versions of the scene for reads and renders with `at_version=N`: loaded from the data
// directory beside the live scene (engine/durable/past_version.h), the last few kept loaded so
// that several frames or reads of one version pay the load once.

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <utility>

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
    /// Past scenes are made with `config`; at most `keep` are held.
    explicit PastScenes(EngineConfig config, std::size_t keep = 2)
        : m_config(std::move(config)), m_keep(keep) {}

    /// The engine at `version`: `live` itself at its own version; an older version loaded from
    /// `store` (or found loaded). NotFound-like errors say why not: OutOfRange for a version the
    /// directory does not hold (or that does not exist yet), InvalidArgument without a data
    /// directory.
    Result<std::shared_ptr<Engine>> at(Engine& live, durable::DurableStore* store,
                                       uint64_t version);

private:
    EngineConfig m_config;
    std::size_t m_keep;
    std::mutex m_mutex;  ///< held while loading: one load at a time, none twice
    std::deque<std::pair<uint64_t, std::shared_ptr<Engine>>> m_loaded;  ///< newest use last
};

}  // namespace strata::server

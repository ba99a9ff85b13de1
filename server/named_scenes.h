#pragma once
// Named scenes (/v1/scenes): scenes beside the default one, each with its own engine (so its own
// version, budget, undo history and Embree device), its own data directory
// (--data/scenes/NAME/: journal, snapshots and scene.json, its settings), its own viewer streams
// and past versions, and its own route table: every /v1 route, bound to that scene's context.
// /v1/scenes/NAME/REST is served as /v1/REST by that table (scene_path.h); the default scene
// keeps the unprefixed paths and the server's own store, streams and edit log.
//
// Lifetime. A request holds its scene (a shared_ptr) while it runs. Deleting a scene takes it
// out of the directory at once (later requests get 404) and renames its data directory to
// scenes/.deleted-NAME-N; the engine, the store and the directory's files go when the last
// request still using the scene ends. Until then a PUT of the same name is a 409 scene-conflict,
// so two stores never share one directory. Leftover .deleted-* and .new-* directories (a crash
// in between) are removed when the server starts.

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "engine/engine.h"
#include "protocol/problem.h"
#include "server/route_table.h"

namespace strata::durable {
class DurableStore;
struct StoreOptions;
}

namespace strata::server {

struct FrontEndCounters;
struct ServerConfig;
struct ServerContext;
class ServerMetrics;
class StreamHub;

/// The data directory options the flags set (--fsync, --snapshot-threshold-kb, ...), for `dir`.
durable::StoreOptions store_options(const ServerConfig& c, const std::string& dir);

/// Whether two budgets set the same limits.
bool same_budget(const SceneBudget& a, const SceneBudget& b);

/// What every named scene shares with the server.
struct SceneShared {
    const ServerConfig& config;
    ServerMetrics& metrics;
    const FrontEndCounters* front_end = nullptr;
    std::function<bool()> api_busy;  ///< true while API renders or commits are queued or running
};

class HostedScene {
public:
    ~HostedScene();
    HostedScene(const HostedScene&) = delete;
    HostedScene& operator=(const HostedScene&) = delete;

    const std::string& name() const { return m_name; }
    const SceneBudget& budget() const { return m_budget; }
    Engine& engine() { return *m_engine; }
    bool durable() const { return m_store != nullptr; }
    /// Every /v1 route, bound to this scene.
    const RouteTable& routes() const { return m_routes; }
    StreamHub& streams() { return *m_streams; }

private:
    friend class SceneDirectory;
    HostedScene() = default;

    std::string m_name;
    SceneBudget m_budget;
    std::unique_ptr<Engine> m_engine;
    std::unique_ptr<durable::DurableStore> m_store;
    std::unique_ptr<StreamHub> m_streams;
    std::unique_ptr<ServerContext> m_context;  ///< before m_routes: its handlers refer to it
    RouteTable m_routes;
    std::string m_trash;               ///< deleted: its renamed data directory, removed last
    std::function<void()> m_on_gone;   ///< deleted: tells the directory the name is free
};

class SceneDirectory {
public:
    explicit SceneDirectory(SceneShared shared);
    ~SceneDirectory();
    SceneDirectory(const SceneDirectory&) = delete;
    SceneDirectory& operator=(const SceneDirectory&) = delete;

    /// With --data: opens and recovers every scene under --data/scenes/. An error names the
    /// scene and the cause (the server does not start without its scenes).
    Status recover();

    /// The scene `name`, made with `budget` (created: true), or the one that exists (false; a
    /// scene-conflict problem when it holds another budget); a creation of the same name in
    /// progress is waited for. Problems: a full directory (--max-scenes, 413), a name still
    /// being deleted (409), storage (503). The files are written outside the directory's lock.
    Expected<std::pair<std::shared_ptr<HostedScene>, bool>, protocol::Problem> create(
        const std::string& name, const SceneBudget& budget);
    /// The scene `name`, or null.
    std::shared_ptr<HostedScene> find(std::string_view name) const;
    /// Deletes `name` (see Lifetime above); false when there is no such scene.
    bool remove(const std::string& name);
    /// Every named scene, by name.
    std::vector<std::shared_ptr<HostedScene>> list() const;
    /// Ends every named scene's streams (the server is shutting down).
    void stop_streams();

    /// The budget a scene gets when PUT names none: the server's --max-scene-* flags.
    SceneBudget default_budget() const;

private:
    /// A new scene with its files (with --data) and engine; `serial` names its temporary
    /// directory.
    Expected<std::shared_ptr<HostedScene>, protocol::Problem> build(const std::string& name,
                                                                    const SceneBudget& budget,
                                                                    uint64_t serial);
    /// A new scene in memory, with its store opened in `dir` when not empty.
    Result<std::shared_ptr<HostedScene>> open(const std::string& name, const SceneBudget& budget,
                                              const std::string& dir);
    /// --data/scenes, or "" without --data.
    std::string root() const;
    /// Why `budget` does not fit in the server-wide budget beside the scenes held, being made
    /// and still going (--max-total-*), or "" when it fits. Under m_mutex.
    std::string over_total(const SceneBudget& budget) const;

    SceneShared m_shared;
    mutable std::mutex m_mutex;
    std::map<std::string, std::shared_ptr<HostedScene>, std::less<>> m_scenes;
    /// Names whose files and engine are being made, with their budgets.
    std::map<std::string, SceneBudget, std::less<>> m_creating;
    std::condition_variable m_created;   ///< a creation ended
    /// Scenes deleted that still live (a request holds them), by name with their budgets (still
    /// counted against --max-total-*); shared with the scenes, which leave it when destroyed.
    struct Going {
        std::mutex mutex;
        std::map<std::string, SceneBudget, std::less<>> names;
    };
    std::shared_ptr<Going> m_going = std::make_shared<Going>();
    uint64_t m_serial = 0;  ///< for the names of renamed directories
};

}  // namespace strata::server

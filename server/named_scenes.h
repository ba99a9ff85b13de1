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
//
// Shared edit log (--log, follow_log). The named scenes are those of the log's scene directory
// (replica/scene_log.h), shared by every server on the log. A PUT publishes the scene there
// first (one incarnation wins a race) and a DELETE retracts it there first; each scene follows
// its own stream with its own replica (replica.h), so its edits reach every server. A thread
// reconciles this server with the directory every LOG_POLL: it makes the scenes other servers
// created and drops those they deleted (those with a tombstone only, so that a flushed Redis
// loses nothing here); a request naming a scene this server does not hold yet asks the directory
// at once. A scene's incarnation is kept in its data directory (file `log-id`), so a restart
// follows its stream from the recovered version. A scene made without --log has none: it stays
// this server's own, and the log's scene of the same name is not followed here.

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "engine/engine.h"
#include "protocol/problem.h"
#include "server/replica/replica.h"
#include "server/replica/scene_log.h"
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
/// Each of `budget`'s limits, lowered to `ceiling`'s where it is above.
SceneBudget clamp(SceneBudget budget, const SceneBudget& ceiling);

/// What every named scene shares with the server.
struct SceneShared {
    const ServerConfig& config;
    ServerMetrics& metrics;
    const FrontEndCounters* front_end = nullptr;
    std::function<bool()> api_busy;  ///< true while API renders or commits are queued or running
    /// The Embree device the scenes share (their identical meshes share BLASes); null: the
    /// directory makes one for the named scenes.
    std::shared_ptr<SharedEmbree> device = nullptr;
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
    /// Its incarnation in the shared edit log's scene directory; "" when it follows none.
    const std::string& log_id() const { return m_log_id; }

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
    std::string m_log_id;
    std::unique_ptr<replica::Replica> m_replica;  ///< following its stream; null without --log
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
    /// The scene `name`, or null. With the log, a name this server does not hold is looked up
    /// in the log's directory, and made here when it is listed.
    std::shared_ptr<HostedScene> find(std::string_view name);
    /// The version of scene `name` for a read waiting for a min_version (never blocks): 0 for
    /// a scene this server does not hold yet while the log is followed (it may arrive), else
    /// UINT64_MAX (no scene to wait for: the route answers at once).
    uint64_t version_of(std::string_view name) const;
    /// Deletes `name` (see Lifetime above), from the log's directory too; false when there is
    /// no such scene. Problems: Redis unreachable (503).
    Expected<bool, protocol::Problem> remove(const std::string& name);
    /// Follows the shared edit log's scene directory from now on (see Shared edit log above);
    /// `base` is the default scene's replica options. Recovered scenes with an incarnation
    /// start following their streams at once.
    void follow_log(const replica::ReplicaOptions& base);
    /// Every named scene, by name.
    std::vector<std::shared_ptr<HostedScene>> list() const;
    /// Ends every named scene's streams (the server is shutting down).
    void stop_streams();

    /// The Embree device the scenes share, with its pool of shared BLASes.
    const std::shared_ptr<SharedEmbree>& shared_device() const { return m_shared.device; }

    /// The budget a scene gets when PUT names none: the server's --max-scene-* flags.
    SceneBudget default_budget() const;

private:
    using Made = std::pair<std::shared_ptr<HostedScene>, bool>;
    /// create() on this server only, as incarnation `log_id` of the log's scene ("": none). A
    /// scene held under another incarnation is a scene-conflict.
    Expected<Made, protocol::Problem> create_here(const std::string& name,
                                                  const SceneBudget& budget,
                                                  const std::string& log_id);
    /// A new scene with its files (with --data) and engine; `serial` names its temporary
    /// directory.
    Expected<std::shared_ptr<HostedScene>, protocol::Problem> build(const std::string& name,
                                                                    const SceneBudget& budget,
                                                                    const std::string& log_id,
                                                                    uint64_t serial);
    /// A new scene in memory, with its store opened in `dir` when not empty, following its
    /// stream when it has an incarnation and the log is followed.
    Result<std::shared_ptr<HostedScene>> open(const std::string& name, const SceneBudget& budget,
                                              const std::string& log_id, const std::string& dir);
    /// Why a new scene of `budget` does not fit here (--max-scenes, --max-total-*), if it does
    /// not. Under m_mutex.
    std::optional<protocol::Problem> no_room(const SceneBudget& budget) const;
    /// The scene `name` on this server, or null.
    std::shared_ptr<HostedScene> find_here(std::string_view name) const;
    /// remove() on this server only; false when it held no such scene.
    bool drop(const std::string& name);

    /// Starts `scene`'s replica on its stream (under m_mutex, or before anyone sees the scene).
    void follow_stream(HostedScene& scene);
    /// Makes this server hold the log's scene `name` (`entry`), in place of an older
    /// incarnation; false (logged) when it cannot now.
    bool adopt(const std::string& name, const replica::SceneLogEntry& entry);
    /// One pass of the follower: adopts what the directory lists, drops what it deleted.
    void reconcile();
    void follow_loop();
    void stop_following();
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

    // The shared edit log, once follow_log() was called.
    std::unique_ptr<replica::ReplicaOptions> m_log_options;
    std::unique_ptr<replica::SceneLog> m_log;
    std::thread m_follower;
    std::mutex m_follow_mutex;
    std::condition_variable m_follow_wake;
    bool m_follow_stop = false;
    std::string m_follow_error;  ///< the last pass's problem, logged once
    std::map<std::string, std::string> m_unheld;  ///< name -> why not held, logged once
    std::set<std::string> m_retracted;            ///< "NAME ID" this server deleted
    std::atomic<int64_t> m_find_retry_at{0};       ///< steady clock ticks: find() asks again
    std::atomic<bool> m_following{false};          ///< follow_log() ran
};

}  // namespace strata::server

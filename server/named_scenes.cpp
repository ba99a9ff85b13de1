// Named scenes: the directory of engines beside the default scene (named_scenes.h).

#include "server/named_scenes.h"

#include <filesystem>

#include <spdlog/spdlog.h>

#include "engine/core/memory_trim.h"
#include "engine/durable/durable_store.h"
#include "engine/durable/file_io.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/stream_hub.h"

namespace strata::server {

namespace fs = std::filesystem;

namespace {

constexpr const char* SETTINGS_FILE = "scene.json";
/// The scene's incarnation in the shared edit log's directory, when it has one.
constexpr const char* LOG_ID_FILE = "log-id";

protocol::Problem storage_problem(const std::string& what) {
    return protocol::make_problem(protocol::ProblemType::Unavailable, what);
}

/// A budget's limits, for what compares or clamps them all.
constexpr uint64_t SceneBudget::*BUDGET_FIELDS[] = {
    &SceneBudget::max_triangles, &SceneBudget::max_vertices, &SceneBudget::max_instances,
    &SceneBudget::max_texture_bytes};

/// Removes `dir` and what it holds; a failure is logged (nothing else depends on it).
void remove_tree(const std::string& dir) {
    std::error_code ec;
    fs::remove_all(dir, ec);
    if (ec) spdlog::warn("could not remove {}: {}", dir, ec.message());
}

}  // namespace

bool same_budget(const SceneBudget& a, const SceneBudget& b) {
    for (uint64_t SceneBudget::*f : BUDGET_FIELDS)
        if (a.*f != b.*f) return false;
    return true;
}

SceneBudget clamp(SceneBudget budget, const SceneBudget& ceiling) {
    for (uint64_t SceneBudget::*f : BUDGET_FIELDS) budget.*f = std::min(budget.*f, ceiling.*f);
    return budget;
}

durable::StoreOptions store_options(const ServerConfig& c, const std::string& dir) {
    durable::StoreOptions o;
    o.dir = dir;
    o.journal.mode = c.fsync == "batch" ? durable::FsyncMode::Batch
                     : c.fsync == "off" ? durable::FsyncMode::Off
                                        : durable::FsyncMode::Always;
    o.journal.fsync_interval_ms = c.fsync_interval_ms;
    o.recovery.truncate_damage = c.recover_truncate;
    o.snapshot_threshold_bytes = c.snapshot_threshold_kb << 10;
    o.keep_history_bytes = c.keep_history_mb << 20;
    o.on_snapshot_failure = [](const std::string& why) { spdlog::error("{}", why); };
    return o;
}

HostedScene::~HostedScene() {
    m_replica.reset();  // its reader applies to the engine
    m_streams.reset();  // joins its thread, which renders with the engine
    m_context.reset();
    m_store.reset();  // the journal's last fsync, before the engine goes
    m_engine.reset();
    if (!m_trash.empty()) remove_tree(m_trash);
    if (m_on_gone) m_on_gone();
    release_free_memory();
}

SceneDirectory::SceneDirectory(SceneShared shared) : m_shared(std::move(shared)) {
    if (!m_shared.device) {
        auto device = SharedEmbree::create("");
        if (device) m_shared.device = std::move(device.value());
    }
}

SceneDirectory::~SceneDirectory() {
    stop_following();
    stop_streams();
}

std::string SceneDirectory::root() const {
    const std::string& data = m_shared.config.data_dir;
    return data.empty() ? std::string() : durable::join_path(data, "scenes");
}

std::string SceneDirectory::over_total(const SceneBudget& budget) const {
    struct Total {
        uint64_t SceneBudget::*field;
        uint64_t limit;  ///< in the field's unit; 0: none
        const char* what;
        const char* flag;
    };
    const ServerConfig& c = m_shared.config;
    const Total totals[] = {
        {&SceneBudget::max_triangles, c.max_total_triangles, "triangles", "--max-total-triangles"},
        {&SceneBudget::max_vertices, c.max_total_vertices, "vertices", "--max-total-vertices"},
        {&SceneBudget::max_instances, c.max_total_instances, "instances", "--max-total-instances"},
        {&SceneBudget::max_texture_bytes, c.max_total_texture_mb << 20, "texture bytes",
         "--max-total-texture-mb"},
    };
    for (const Total& t : totals) {
        if (t.limit == 0) continue;
        // The default scene's budget is the flags', reserved from the start.
        uint64_t sum = default_budget().*t.field + budget.*t.field;
        for (const auto& [name, scene] : m_scenes) sum += scene->budget().*t.field;
        for (const auto& [name, reserved] : m_creating) sum += reserved.*t.field;
        std::lock_guard going(m_going->mutex);
        for (const auto& [name, reserved] : m_going->names) sum += reserved.*t.field;
        if (sum > t.limit)
            return "the scenes' budgets would add up to " + std::to_string(sum) + " " + t.what +
                   ", over the server's " + std::to_string(t.limit) + " (" + t.flag +
                   "): give the scene a smaller budget, or delete a scene";
    }
    return "";
}

SceneBudget SceneDirectory::default_budget() const {
    return scene_budget(m_shared.config);
}

Result<std::shared_ptr<HostedScene>> SceneDirectory::open(const std::string& name,
                                                          const SceneBudget& budget,
                                                          const std::string& log_id,
                                                          const std::string& dir) {
    std::shared_ptr<HostedScene> scene(new HostedScene());
    scene->m_name = name;
    scene->m_budget = budget;
    scene->m_log_id = log_id;
    EngineConfig config = engine_config(m_shared.config);
    config.budget = budget;
    config.accel.shared_device = m_shared.device;
    auto engine = Engine::create(config);
    if (!engine) return Unexpected(engine.error());
    scene->m_engine = std::move(engine.value());
    if (!dir.empty()) {
        auto store = durable::DurableStore::open(store_options(m_shared.config, dir),
                                                 *scene->m_engine);
        if (!store) return Unexpected(store.error());
        scene->m_store = std::move(store.value());
    }
    scene->m_streams = std::make_unique<StreamHub>(*scene->m_engine, m_shared.api_busy,
                                                   m_shared.config.max_stream_mb << 20);
    scene->m_context = std::make_unique<ServerContext>(ServerContext{
        *scene->m_engine, m_shared.config, m_shared.metrics, api_limits(m_shared.config),
        m_shared.front_end, scene->m_store.get(), nullptr, {}, scene->m_streams.get(), {}});
    scene->m_context->api_limits.budget = budget;
    scene->m_context->past = std::make_unique<PastScenes>(config);
    add_api_routes(scene->m_routes, *scene->m_context);
    add_stream_routes(scene->m_routes, *scene->m_context);
    if (m_log_options && !log_id.empty()) follow_stream(*scene);
    return scene;
}

Status SceneDirectory::recover() {
    const std::string dir = root();
    std::error_code ec;
    if (dir.empty() || !fs::is_directory(dir, ec)) return {};
    std::vector<fs::directory_entry> entries;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        entries.push_back(*it);
    if (ec) return failure(ErrorCode::Storage, "cannot list " + dir + ": " + ec.message());
    for (const fs::directory_entry& entry : entries) {
        const std::string name = entry.path().filename().string();
        if (name.rfind(".deleted-", 0) == 0 || name.rfind(".new-", 0) == 0) {
            spdlog::info("removing {} (left by a scene deletion or creation that did not end)",
                         entry.path().string());
            remove_tree(entry.path().string());
            continue;
        }
        std::error_code kind;
        if (!protocol::valid_scene_name(name) || name == "default" || !entry.is_directory(kind)) {
            spdlog::warn("{}: not a scene (scene names are {}); left alone",
                         entry.path().string(), protocol::SCENE_NAME_RULE);
            continue;
        }
        const std::string path = entry.path().string();
        auto text = durable::read_whole_file(durable::join_path(path, SETTINGS_FILE));
        if (!text) return Unexpected(text.error());
        SceneBudget unlimited{UINT64_MAX, UINT64_MAX, UINT64_MAX, UINT64_MAX};
        auto budget = protocol::parse_scene_settings(text.value(), unlimited, {});
        if (!budget)
            return failure(ErrorCode::Storage, "scene '" + name + "': " +
                                                   durable::join_path(path, SETTINGS_FILE) +
                                                   ": " + budget.error().detail);
        // Its incarnation in the shared edit log, when it was made with one.
        std::string log_id;
        if (auto id = durable::read_whole_file(durable::join_path(path, LOG_ID_FILE))) {
            if (!replica::valid_scene_log_id(id.value()))
                return failure(ErrorCode::Storage,
                               "scene '" + name + "': " + durable::join_path(path, LOG_ID_FILE) +
                                   " is not a scene incarnation (16 hex digits)");
            log_id = id.value();
        }
        auto scene = open(name, clamp(budget.value(), default_budget()), log_id, path);
        if (!scene)
            return failure(ErrorCode::Storage, "scene '" + name + "': " + scene.error().message);
        const Engine& engine = scene.value()->engine();
        if (engine.version() != 0) {
            auto built = scene.value()->engine().commit();
            if (!built)
                spdlog::error("scene '{}': building the recovered scene failed: {}", name,
                              built.error().describe());
        }
        spdlog::info("scene '{}' recovered at version {}", name, engine.version());
        std::lock_guard lock(m_mutex);
        m_scenes.emplace(name, std::move(scene.value()));
    }
    return {};
}

std::optional<protocol::Problem> SceneDirectory::no_room(const SceneBudget& budget) const {
    const std::size_t held = m_scenes.size() + m_creating.size();
    if (held >= m_shared.config.max_scenes)
        return protocol::make_problem(protocol::ProblemType::TooLarge,
                                      "this server holds " + std::to_string(held) +
                                          " named scenes already, its limit (--max-scenes)");
    if (std::string over = over_total(budget); !over.empty()) {
        protocol::Problem p = protocol::make_problem(protocol::ProblemType::TooLarge, over);
        p.pointer = "/budget";
        return p;
    }
    return std::nullopt;
}

Expected<std::pair<std::shared_ptr<HostedScene>, bool>, protocol::Problem> SceneDirectory::create(
    const std::string& name, const SceneBudget& budget) {
    if (!m_log) return create_here(name, budget, "");
    {
        // A scene this server could not hold is not published for the others either.
        std::lock_guard lock(m_mutex);
        if (auto refused = no_room(budget); refused && !m_scenes.count(name))
            return Unexpected(std::move(*refused));
    }
    // Step: the log's directory first: one server's incarnation wins a race for the name.
    auto entry = m_log->publish(name, protocol::scene_settings_json(budget).dump());
    if (!entry)
        return Unexpected(storage_problem("scene '" + name +
                                          "' not created: the edit log's scene directory: " +
                                          entry.error().message));
    auto listed = protocol::parse_scene_settings(entry->settings, default_budget(), {});
    if (!listed || !same_budget(listed.value(), budget))
        return Unexpected(protocol::make_problem(
            protocol::ProblemType::SceneConflict,
            "scene '" + name + "' exists with another budget; delete it first to change it"));
    auto made = create_here(name, budget, entry->id);
    if (!made && entry->created) (void)m_log->retract(name, entry->id);  // nobody saw it
    if (made) made->second = entry->created;
    return made;
}

Expected<SceneDirectory::Made, protocol::Problem> SceneDirectory::create_here(
    const std::string& name, const SceneBudget& budget, const std::string& log_id) {
    std::unique_lock lock(m_mutex);
    // A PUT of a name another PUT is creating waits for it, then finds its scene.
    m_created.wait(lock, [&] { return m_creating.find(name) == m_creating.end(); });
    if (auto it = m_scenes.find(name); it != m_scenes.end()) {
        if (!same_budget(it->second->budget(), budget))
            return Unexpected(protocol::make_problem(
                protocol::ProblemType::SceneConflict,
                "scene '" + name + "' exists with another budget; delete it first to change it"));
        if (it->second->log_id() != log_id)
            return Unexpected(protocol::make_problem(
                protocol::ProblemType::SceneConflict,
                "scene '" + name + "' is held here as " +
                    (it->second->log_id().empty() ? "this server's own scene"
                                                  : "an older incarnation") +
                    ", not the edit log's; try again once it is replaced"));
        return std::pair(it->second, false);
    }
    {
        std::lock_guard going(m_going->mutex);
        if (m_going->names.find(name) != m_going->names.end())
            return Unexpected(protocol::make_problem(
                protocol::ProblemType::SceneConflict,
                "scene '" + name +
                    "' is still being deleted (a request still uses it); try again"));
    }
    if (auto refused = no_room(budget)) return Unexpected(std::move(*refused));
    // Step: the files and the engine, outside the lock (fsyncs take a while; other scenes' requests
    // go on), the name reserved meanwhile.
    m_creating.emplace(name, budget);
    const uint64_t serial = ++m_serial;
    lock.unlock();
    auto made = build(name, budget, log_id, serial);
    lock.lock();
    m_creating.erase(name);
    if (made) m_scenes.emplace(name, made.value());
    m_created.notify_all();
    if (!made) return Unexpected(std::move(made).error());
    return std::pair(std::move(made.value()), true);
}

Expected<std::shared_ptr<HostedScene>, protocol::Problem> SceneDirectory::build(
    const std::string& name, const SceneBudget& budget, const std::string& log_id,
    uint64_t serial) {
    std::string dir;
    if (const std::string parent = root(); !parent.empty()) {
        // Step: the directory and its settings, made under a temporary name and renamed, so that
        // a crash leaves either no scene or a whole one.
        std::error_code ec;
        fs::create_directories(parent, ec);
        const std::string fresh =
            durable::join_path(parent, ".new-" + name + "-" + std::to_string(serial));
        fs::create_directories(fresh, ec);
        if (ec) return Unexpected(storage_problem("cannot create " + fresh + ": " + ec.message()));
        const std::string settings = protocol::scene_settings_json(budget).dump(1) + "\n";
        dir = durable::join_path(parent, name);
        Status written = durable::write_file_atomically(fresh, SETTINGS_FILE, settings);
        if (written && !log_id.empty())
            written = durable::write_file_atomically(fresh, LOG_ID_FILE, log_id);
        if (written && ::rename(fresh.c_str(), dir.c_str()) != 0)
            written = failure(ErrorCode::Storage,
                              durable::errno_message("cannot rename " + fresh + " to " + dir));
        if (written) written = durable::sync_directory(parent);
        if (!written) {
            remove_tree(fresh);
            return Unexpected(storage_problem(written.error().message));
        }
    }
    auto scene = open(name, budget, log_id, dir);
    if (!scene) {
        if (!dir.empty()) remove_tree(dir);
        return Unexpected(storage_problem("scene '" + name + "': " + scene.error().message));
    }
    spdlog::info("scene '{}' created{}", name, dir.empty() ? " (in memory)" : " in " + dir);
    return std::move(scene.value());
}

std::shared_ptr<HostedScene> SceneDirectory::find_here(std::string_view name) const {
    std::lock_guard lock(m_mutex);
    const auto it = m_scenes.find(name);
    return it == m_scenes.end() ? nullptr : it->second;
}

bool SceneDirectory::drop(const std::string& name) {
    std::shared_ptr<HostedScene> scene;
    {
        std::lock_guard lock(m_mutex);
        const auto it = m_scenes.find(name);
        if (it == m_scenes.end()) return false;
        scene = std::move(it->second);
        m_scenes.erase(it);
        std::lock_guard going(m_going->mutex);
        m_going->names.emplace(name, scene->budget());
        // Step: the files leave the scene's name at once; they are removed with the scene.
        if (scene->m_store) {
            const std::string dir = scene->m_store->directory();
            const std::string trash = durable::join_path(
                root(), ".deleted-" + name + "-" + std::to_string(++m_serial));
            if (::rename(dir.c_str(), trash.c_str()) == 0) {
                scene->m_trash = trash;
                (void)durable::sync_directory(root());
            } else {
                spdlog::error("{}; its files are left in place",
                              durable::errno_message("cannot rename " + dir + " to " + trash));
            }
        }
    }
    scene->m_streams->stop();
    if (scene->m_replica) scene->m_replica->stop();  // its stream is gone or going
    scene->m_on_gone = [going = m_going, name] {
        std::lock_guard lock(going->mutex);
        going->names.erase(name);
    };
    spdlog::info("scene '{}' deleted", name);
    return true;  // the last holder of `scene` frees it
}

std::vector<std::shared_ptr<HostedScene>> SceneDirectory::list() const {
    std::lock_guard lock(m_mutex);
    std::vector<std::shared_ptr<HostedScene>> out;
    for (const auto& [name, scene] : m_scenes) out.push_back(scene);
    return out;
}

void SceneDirectory::stop_streams() {
    for (const auto& scene : list()) scene->m_streams->stop();
}

}  // namespace strata::server

// Named scenes on a shared edit log: the part of the scene directory that follows the log's
// scene directory (named_scenes.h, "Shared edit log").

#include <spdlog/spdlog.h>

#include "engine/durable/durable_store.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/named_scenes.h"

namespace strata::server {

namespace {

/// How often the follower reconciles this server with the log's scene directory.
constexpr std::chrono::milliseconds LOG_POLL{250};
/// How long a request naming an unknown scene does not ask Redis again after it failed.
constexpr std::chrono::milliseconds FIND_BACKOFF{1000};
/// Incarnations this server deleted, remembered so that a pass of the follower that read the
/// directory before the deletion does not make them again.
constexpr std::size_t MAX_RETRACTED = 10000;

}  // namespace

void SceneDirectory::follow_log(const replica::ReplicaOptions& base) {
    m_log_options = std::make_unique<replica::ReplicaOptions>(base);
    m_log = std::make_unique<replica::SceneLog>(base.url);
    {
        std::lock_guard lock(m_mutex);
        for (auto& [name, scene] : m_scenes) {
            if (scene->log_id().empty()) {
                spdlog::warn("scene '{}' was made without --log: it stays this server's own and "
                             "is not replicated",
                             name);
                continue;
            }
            follow_stream(*scene);
        }
    }
    m_follower = std::thread([this] { follow_loop(); });
    m_following = true;
}

uint64_t SceneDirectory::version_of(std::string_view name) const {
    if (const auto scene = find_here(name)) return scene->m_engine->version();
    return m_following ? 0 : UINT64_MAX;
}

void SceneDirectory::follow_stream(HostedScene& scene) {
    replica::ReplicaOptions o = *m_log_options;
    o.url = m_log->scene_url(scene.m_name, scene.m_log_id);
    o.store = scene.m_store.get();
    scene.m_replica = replica::Replica::start(o, *scene.m_engine);
    scene.m_context->attach_replica(scene.m_replica.get());
    spdlog::info("scene '{}' follows the edit log {} from version {}", scene.m_name,
                 o.url.describe(), scene.m_engine->version());
}

std::shared_ptr<HostedScene> SceneDirectory::find(std::string_view name) {
    if (auto scene = find_here(name); scene || !m_log) return scene;
    // Made on another server a moment ago: the directory lists it before the follower ran.
    const int64_t now = std::chrono::steady_clock::now().time_since_epoch().count();
    if (now < m_find_retry_at.load(std::memory_order_relaxed)) return nullptr;
    const std::string wanted(name);
    auto entry = m_log->find(wanted);
    if (!entry) {
        const auto backoff = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            FIND_BACKOFF);
        m_find_retry_at.store(now + backoff.count(), std::memory_order_relaxed);
        return nullptr;
    }
    if (!entry.value() || !adopt(wanted, *entry.value())) return nullptr;
    return find_here(name);
}

Expected<bool, protocol::Problem> SceneDirectory::remove(const std::string& name) {
    if (!m_log) return drop(name);
    const auto not_deleted = [&](const Error& e) {
        return Unexpected(protocol::make_problem(
            protocol::ProblemType::Unavailable,
            "scene '" + name + "' not deleted: the edit log's scene directory: " + e.message));
    };
    const std::shared_ptr<HostedScene> held = find_here(name);
    std::string id = held ? held->log_id() : std::string();
    if (!held) {
        auto entry = m_log->find(name);
        if (!entry) return not_deleted(entry.error());
        if (entry.value()) id = entry.value()->id;
    }
    bool retracted = false;
    if (!id.empty()) {
        {
            std::lock_guard lock(m_follow_mutex);
            if (m_retracted.size() >= MAX_RETRACTED) m_retracted.clear();
            m_retracted.insert(name + " " + id);
        }
        auto done = m_log->retract(name, id);
        if (!done) return not_deleted(done.error());
        retracted = done.value();
    }
    return drop(name) || retracted;
}

bool SceneDirectory::adopt(const std::string& name, const replica::SceneLogEntry& entry) {
    const auto unheld = [&](const std::string& why) {
        std::lock_guard lock(m_follow_mutex);
        std::string& said = m_unheld[name];
        if (said != entry.id + why)
            spdlog::warn("scene '{}' of the edit log is not held here: {}", name, why);
        said = entry.id + why;
        return false;
    };
    {
        std::lock_guard lock(m_follow_mutex);
        if (m_retracted.count(name + " " + entry.id)) return false;
    }
    if (const auto held = find_here(name)) {
        if (held->log_id() == entry.id) return true;
        if (held->log_id().empty()) return unheld("this server holds its own scene of that name");
        spdlog::info("scene '{}': incarnation {} replaces {}", name, entry.id, held->log_id());
        drop(name);
    }
    SceneBudget unlimited{UINT64_MAX, UINT64_MAX, UINT64_MAX, UINT64_MAX};
    auto budget = protocol::parse_scene_settings(entry.settings, unlimited, {});
    if (!budget) return unheld("its settings: " + budget.error().detail);
    auto made = create_here(name, clamp(budget.value(), default_budget()), entry.id);
    if (!made) return unheld(made.error().detail);
    {
        std::lock_guard lock(m_follow_mutex);
        m_unheld.erase(name);
    }
    if (made->second) spdlog::info("scene '{}' joined from the edit log", name);
    return true;
}

void SceneDirectory::reconcile() {
    const auto note = [&](const std::string& problem) {
        if (problem != m_follow_error)
            spdlog::warn("following the edit log's scene directory: {}", problem);
        m_follow_error = problem;
    };
    auto listed = m_log->list();
    if (!listed) return note(listed.error().message);
    for (const auto& [name, entry] : listed.value()) adopt(name, entry);
    for (const auto& scene : list()) {
        const std::string& id = scene->log_id();
        const auto it = listed->find(scene->name());
        if (id.empty() || (it != listed->end() && it->second.id == id)) continue;
        auto deleted = m_log->deleted(scene->name(), id);
        if (!deleted) return note(deleted.error().message);
        if (deleted.value()) {
            spdlog::info("scene '{}' was deleted on another server", scene->name());
            drop(scene->name());
        } else if (it == listed->end()) {
            note("scene '" + scene->name() + "' is gone from " + m_log->key() +
                 " without a tombstone (was Redis emptied?): this server keeps its copy");
            continue;
        }
    }
    m_follow_error.clear();
}

void SceneDirectory::follow_loop() {
    std::unique_lock lock(m_follow_mutex);
    while (!m_follow_stop) {
        lock.unlock();
        reconcile();
        lock.lock();
        m_follow_wake.wait_for(lock, LOG_POLL, [&] { return m_follow_stop; });
    }
}

void SceneDirectory::stop_following() {
    {
        std::lock_guard lock(m_follow_mutex);
        m_follow_stop = true;
    }
    m_follow_wake.notify_all();
    if (m_follower.joinable()) m_follower.join();
}

}  // namespace strata::server

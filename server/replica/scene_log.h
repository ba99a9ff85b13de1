#pragma once
// The named scenes of a shared edit log (--log redis://HOST:PORT/STREAM): which scenes exist,
// with which settings, and the stream each one's edits go to. The default scene's log is STREAM
// itself. The directory is the hash STREAM:scenes, one field per scene name, whose value is
// "ID SETTINGS": ID a random incarnation of 16 hex digits (a scene deleted and made again gets a
// new one, so its new log never meets the old one's entries) and SETTINGS its settings as PUT
// /v1/scenes/NAME takes them. Scene NAME's edits go to the stream STREAM:scene:NAME:ID, with
// that stream's :version and :snapshot keys (redis_url.h), and a replica follows it as it
// follows the default scene's (replica.h).
//
// Creation and deletion are one script each, so two servers that create one name at once agree
// on one incarnation, and a deletion removes the incarnation it was asked about only. A deletion
// leaves a tombstone, "NAME ID" in the sorted set STREAM:scenes:deleted (the newest 10,000
// kept): a server drops its copy of a scene the directory no longer lists only when its
// tombstone says it was deleted, never because the directory was emptied (a flushed Redis).

#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "engine/core/result.h"
#include "server/replica/redis_url.h"

namespace strata::replica {

class RedisConnection;

/// One scene of the directory.
struct SceneLogEntry {
    std::string id;        ///< the incarnation
    std::string settings;  ///< its settings, as they were published
    bool created = false;  ///< publish() made it (false: it existed)
};

class SceneLog {
public:
    explicit SceneLog(RedisUrl log);
    ~SceneLog();
    SceneLog(const SceneLog&) = delete;
    SceneLog& operator=(const SceneLog&) = delete;

    /// Adds scene `name` with `settings` and a new incarnation unless the directory lists it;
    /// the entry the directory holds afterwards. Redis unreachable: a Storage error.
    Result<SceneLogEntry> publish(const std::string& name, const std::string& settings);
    /// Removes `name` from the directory, and its log's keys, if it is still incarnation `id`;
    /// whether it was.
    Result<bool> retract(const std::string& name, const std::string& id);
    /// The scene `name`, if the directory lists it.
    Result<std::optional<SceneLogEntry>> find(const std::string& name);
    /// Every scene the directory lists, by name.
    Result<std::map<std::string, SceneLogEntry>> list();
    /// Whether incarnation `id` of `name` was deleted (its tombstone is there).
    Result<bool> deleted(const std::string& name, const std::string& id);

    /// The log of scene `name` in incarnation `id`.
    RedisUrl scene_url(const std::string& name, const std::string& id) const;
    /// The directory's key, STREAM:scenes.
    std::string key() const { return m_log.stream + ":scenes"; }
    /// The tombstones' key, STREAM:scenes:deleted.
    std::string tombstones_key() const { return key() + ":deleted"; }

private:
    /// The connection, made (again) on demand; one command at a time.
    Result<RedisConnection*> connection();

    const RedisUrl m_log;
    std::mutex m_mutex;
    std::unique_ptr<RedisConnection> m_connection;
};

/// Whether `id` is an incarnation: 16 lower-case hex digits.
bool valid_scene_log_id(std::string_view id);
/// A directory value, "ID SETTINGS", read back; nullopt when it is not one.
std::optional<SceneLogEntry> parse_scene_log_value(const std::string& value);

}  // namespace strata::replica

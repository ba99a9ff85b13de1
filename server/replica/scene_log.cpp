// The named scenes of a shared edit log (scene_log.h).

#include "server/replica/scene_log.h"

#include <algorithm>
#include <cstdio>
#include <random>

#include "server/replica/redis_connection.h"
#include "server/replica/replica_util.h"

namespace strata::replica {

namespace {

constexpr std::size_t ID_DIGITS = 16;
constexpr milliseconds COMMAND_TIMEOUT{2000};

// Sets field ARGV[1] of hash KEYS[1] to ARGV[2] unless it is set; returns {1 or 0, the value}.
const std::string PUBLISH_SCRIPT = R"lua(
if redis.call('HSETNX', KEYS[1], ARGV[1], ARGV[2]) == 1 then return {1, ARGV[2]} end
return {0, redis.call('HGET', KEYS[1], ARGV[1])}
)lua";

// Deletes field ARGV[1] of KEYS[1] and the keys KEYS[2..4] if its value starts with ARGV[2]
// and a space, and leaves the tombstone "ARGV[1] ARGV[2]" in KEYS[5] scored ARGV[3] (the newest
// TOMBSTONES kept); returns 1 if it did.
const std::string RETRACT_SCRIPT = R"lua(
local v = redis.call('HGET', KEYS[1], ARGV[1])
if not v or string.sub(v, 1, string.len(ARGV[2]) + 1) ~= ARGV[2] .. ' ' then return 0 end
redis.call('HDEL', KEYS[1], ARGV[1])
redis.call('DEL', KEYS[2], KEYS[3], KEYS[4])
redis.call('ZADD', KEYS[5], ARGV[3], ARGV[1] .. ' ' .. ARGV[2])
redis.call('ZREMRANGEBYRANK', KEYS[5], 0, -10001)
return 1
)lua";

/// The error of a directory value that is not "ID SETTINGS".
Unexpected<Error> damaged(const std::string& directory, const std::string& name) {
    return storage("Redis: the scene directory " + directory + " holds a damaged entry for '" +
                   name.substr(0, 80) + "'");
}

std::string new_id() {
    std::random_device random;
    const uint64_t bits = (uint64_t(random()) << 32) ^ random();
    char text[ID_DIGITS + 1];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(bits));
    return text;
}

}  // namespace

bool valid_scene_log_id(std::string_view id) {
    return id.size() == ID_DIGITS && std::all_of(id.begin(), id.end(), [](char c) {
               return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
           });
}

std::optional<SceneLogEntry> parse_scene_log_value(const std::string& value) {
    if (value.size() < ID_DIGITS + 2 || value[ID_DIGITS] != ' ' ||
        !valid_scene_log_id(std::string_view(value).substr(0, ID_DIGITS)))
        return std::nullopt;
    return SceneLogEntry{value.substr(0, ID_DIGITS), value.substr(ID_DIGITS + 1)};
}

SceneLog::SceneLog(RedisUrl log) : m_log(std::move(log)) {}

SceneLog::~SceneLog() = default;

RedisUrl SceneLog::scene_url(const std::string& name, const std::string& id) const {
    RedisUrl url = m_log;
    url.stream = m_log.stream + ":scene:" + name + ":" + id;
    return url;
}

Result<RedisConnection*> SceneLog::connection() {
    if (m_connection && !m_connection->broken()) return m_connection.get();
    auto made = RedisConnection::connect(m_log, CONNECT_TIMEOUT, COMMAND_TIMEOUT);
    if (!made) return Unexpected(made.error());
    m_connection = std::move(made.value());
    return m_connection.get();
}

Result<SceneLogEntry> SceneLog::publish(const std::string& name, const std::string& settings) {
    std::lock_guard lock(m_mutex);
    auto c = connection();
    if (!c) return Unexpected(c.error());
    const std::string value = new_id() + " " + settings;
    const std::string directory = key();
    auto answer = c.value()->eval(PUBLISH_SCRIPT, {directory}, {name, value});
    if (!answer) return Unexpected(answer.error());
    const RedisReply& r = answer.value();
    if (r.elements.size() != 2 || r.elements[1].type != RedisReply::Type::String)
        return storage("Redis: the scene directory " + directory + " answered no entry for '" +
                       name + "'");
    auto entry = parse_scene_log_value(r.elements[1].str);
    if (!entry) return damaged(directory, name);
    entry->created = r.elements[0].integer == 1;
    return *entry;
}

Result<bool> SceneLog::retract(const std::string& name, const std::string& id) {
    std::lock_guard lock(m_mutex);
    auto c = connection();
    if (!c) return Unexpected(c.error());
    const RedisUrl url = scene_url(name, id);
    const std::string directory = key(), version = url.version_key(),
                      snapshot = url.snapshot_key(), tombstones = tombstones_key(),
                      now = std::to_string(unix_ms());
    auto answer = c.value()->eval(RETRACT_SCRIPT,
                                  {directory, url.stream, version, snapshot, tombstones},
                                  {name, id, now});
    if (!answer) return Unexpected(answer.error());
    return answer.value().integer == 1;
}

Result<bool> SceneLog::deleted(const std::string& name, const std::string& id) {
    std::lock_guard lock(m_mutex);
    auto c = connection();
    if (!c) return Unexpected(c.error());
    const std::string tombstones = tombstones_key(), member = name + " " + id;
    auto answer = c.value()->command({"ZSCORE", tombstones, member});
    if (!answer) return Unexpected(answer.error());
    return !answer.value().is_nil();
}

Result<std::optional<SceneLogEntry>> SceneLog::find(const std::string& name) {
    std::lock_guard lock(m_mutex);
    auto c = connection();
    if (!c) return Unexpected(c.error());
    const std::string directory = key();
    auto answer = c.value()->command({"HGET", directory, name});
    if (!answer) return Unexpected(answer.error());
    if (answer.value().is_nil()) return std::optional<SceneLogEntry>();
    auto entry = parse_scene_log_value(answer.value().str);
    if (!entry) return damaged(directory, name);
    return entry;
}

Result<std::map<std::string, SceneLogEntry>> SceneLog::list() {
    std::lock_guard lock(m_mutex);
    auto c = connection();
    if (!c) return Unexpected(c.error());
    const std::string directory = key();
    auto answer = c.value()->command({"HGETALL", directory});
    if (!answer) return Unexpected(answer.error());
    const auto& fields = answer.value().elements;
    std::map<std::string, SceneLogEntry> out;
    for (std::size_t i = 0; i + 1 < fields.size(); i += 2) {
        auto entry = parse_scene_log_value(fields[i + 1].str);
        if (!entry) return damaged(directory, fields[i].str);
        out.emplace(fields[i].str, std::move(*entry));
    }
    return out;
}

}  // namespace strata::replica

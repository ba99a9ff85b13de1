#include "server/replica/snapshot_writer.h"

#include <spdlog/spdlog.h>

#include "engine/durable/journal_format.h"
#include "server/replica/redis_connection.h"

namespace strata::replica {

namespace {

// Stores snapshot ARGV[2] of version ARGV[1] when newer than the stored one, then trims the
// stream below the snapshot it replaced. Returns {stored 0/1, the stored version, trimmed}.
const std::string SNAPSHOT_SCRIPT = R"lua(
local cur = tonumber(redis.call('HGET', KEYS[1], 'version') or '0')
local v = tonumber(ARGV[1])
if v <= cur then return {0, cur, 0} end
redis.call('HSET', KEYS[1], 'version', ARGV[1], 'bytes', ARGV[2])
local trimmed = 0
if cur > 0 then trimmed = redis.call('XTRIM', KEYS[2], 'MINID', string.format('%d-0', cur + 1)) end
return {1, v, trimmed}
)lua";

constexpr milliseconds SNAPSHOT_COMMAND_TIMEOUT{30000};

}  // namespace

void SnapshotWriter::start() {
    m_thread = std::thread([this] { loop(); });
}

void SnapshotWriter::due() {
    {
        std::lock_guard lock(m_mutex);
        m_due = true;
    }
    m_cv.notify_one();
}

void SnapshotWriter::stop() {
    {
        std::lock_guard lock(m_mutex);
        m_stopping = true;
    }
    m_cv.notify_all();
    if (m_thread.joinable()) m_thread.join();
}

void SnapshotWriter::loop() {
    for (;;) {
        {
            std::unique_lock lock(m_mutex);
            m_cv.wait(lock, [&] { return m_due || m_stopping; });
            m_due = false;
            if (m_stopping) return;
        }
        if (Status s = write(); !s)
            spdlog::warn("edit log snapshot not stored (the log keeps its entries): {}",
                         s.error().message);
    }
}

Status SnapshotWriter::write() {
    auto made = RedisConnection::connect(m_url, CONNECT_TIMEOUT, SNAPSHOT_COMMAND_TIMEOUT);
    if (!made) return Unexpected(made.error());
    RedisConnection& c = *made.value();
    // Step: another replica may have stored this version already.
    auto stored = c.command({"HGET", m_url.snapshot_key(), "version"});
    if (!stored) return Unexpected(stored.error());
    uint64_t have = 0;
    if (!stored.value().is_nil()) (void)parse_u64(stored.value().str, have);
    m_state.know_snapshot(have);
    SceneImage image = m_engine.read([](const Scene& s) { return s.image(); });
    if (image.version <= have) return {};
    // Step: encoded outside the scene lock, stored and trimmed in one script.
    const std::string bytes = durable::encode_snapshot(image.to_batch(), image.version);
    const uint64_t version = image.version;
    image = {};
    auto reply = c.eval(SNAPSHOT_SCRIPT, {m_url.snapshot_key(), m_url.stream},
                        {std::to_string(version), bytes});
    if (!reply) return Unexpected(reply.error());
    const RedisReply& r = reply.value();
    if (r.elements.size() != 3) return storage("the snapshot script answered something unexpected");
    m_state.know_snapshot(uint64_t(r.elements[1].integer));
    if (r.elements[0].integer == 1) {
        m_state.count(&ReplicaStatus::snapshots_written);
        m_state.count(&ReplicaStatus::entries_trimmed, uint64_t(r.elements[2].integer));
        spdlog::info(
            "edit log: stored the snapshot of version {} ({} bytes) in {}; trimmed {} entries",
            version, bytes.size(), m_url.snapshot_key(), r.elements[2].integer);
    }
    return {};
}

}  // namespace strata::replica

#include "server/replica/log_reader.h"

#include <algorithm>
#include <cstring>

#include <spdlog/spdlog.h>

#include "engine/durable/durable_store.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "server/replica/log_entry.h"
#include "server/replica/redis_connection.h"

namespace strata::replica {

namespace {

constexpr milliseconds READER_COMMAND_TIMEOUT{5000};  // above XREAD's BLOCK
constexpr const char* BLOCK_MS = "1000";
constexpr const char* READ_COUNT = "256";

// The log's version key and the id of its newest entry, read at once (the append script writes
// both at once): {version or nil, id or nil}.
const std::string LOG_HEAD_SCRIPT = R"lua(
local newest = redis.call('XREVRANGE', KEYS[1], '+', '-', 'COUNT', 1)
local id = false
if #newest > 0 then id = newest[1][1] end
return {redis.call('GET', KEYS[2]), id}
)lua";

}  // namespace

void LogReader::start() {
    m_thread = std::thread([this] { loop(); });
}

void LogReader::join() {
    if (m_thread.joinable()) m_thread.join();
}

void LogReader::loop() {
    std::unique_ptr<RedisConnection> conn;
    milliseconds backoff = BACKOFF_FIRST;
    bool had_connection = false;
    bool warned = false;
    while (!m_state.shutting_down() && !m_state.stopped()) {
        if (!conn) {
            auto made =
                RedisConnection::connect(m_options.url, CONNECT_TIMEOUT, READER_COMMAND_TIMEOUT);
            if (!made) {
                if (!warned)
                    spdlog::warn(
                        "edit log: {}; retrying with backoff (writes answer 503 "
                        "meanwhile, reads serve version {})",
                        made.error().message, m_state.applied());
                warned = true;
                if (!m_state.sleep_for(backoff)) break;
                backoff = std::min(backoff * 2, BACKOFF_MAX);
                continue;
            }
            conn = std::move(made.value());
            if (Status s = on_connect(*conn); !s) {
                conn.reset();
                if (m_state.stopped()) break;
                if (!m_state.sleep_for(backoff)) break;
                backoff = std::min(backoff * 2, BACKOFF_MAX);
                continue;
            }
            if (had_connection) m_state.count(&ReplicaStatus::reconnects);
            if (warned || had_connection)
                spdlog::info("edit log {} reachable again at version {} (applied {})",
                             m_options.url.describe(), m_state.log_version(), m_state.applied());
            had_connection = true;
            warned = false;
            backoff = BACKOFF_FIRST;
            m_state.set_connected(true);
        }
        if (Status s = read_and_apply(*conn); !s) {
            if (m_state.stopped() || m_state.shutting_down()) break;
            spdlog::warn("edit log: {}; reconnecting", s.error().message);
            conn.reset();
            m_state.set_connected(false);
            warned = true;
        }
    }
    m_state.set_connected(false);
}

Status LogReader::on_connect(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    // Step: the log's head, and the snapshot an empty replica starts from.
    auto head = read_log_head(c);
    if (!head) return Unexpected(head.error());
    const uint64_t log_version = head.value();
    auto snap_version = c.command({"HGET", url.snapshot_key(), "version"});
    if (!snap_version) return Unexpected(snap_version.error());
    uint64_t snapshot = 0;
    if (!snap_version.value().is_nil()) (void)parse_u64(snap_version.value().str, snapshot);
    m_state.know_snapshot(snapshot);

    const uint64_t applied = m_state.applied();
    // Step: an empty replica starts from the snapshot; one holding a scene jumps to it only when
    // the entries after its version were trimmed away.
    if (applied == 0 && snapshot > 0) {
        if (Status s = load_snapshot(c, 0, ""); !s) return s;
    } else if (snapshot > applied && log_version > applied) {
        auto held = holds_entry_after(c, applied);
        if (!held) return Unexpected(held.error());
        if (!held.value()) {
            const std::string gap = "the log (at version " + std::to_string(log_version) +
                                    ") no longer holds the entries after version " +
                                    std::to_string(applied);
            if (Status s = load_snapshot(c, applied, gap); !s) return s;
        }
    }
    m_state.raise_log_version(log_version);
    if (!m_state.joined()) {
        m_join_target = log_version;
        if (m_state.applied() >= m_join_target) m_state.mark_joined();
    }
    return {};
}

Status LogReader::read_and_apply(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    const std::string after = entry_id(m_state.applied());
    auto reply =
        c.command({"XREAD", "COUNT", READ_COUNT, "BLOCK", BLOCK_MS, "STREAMS", url.stream, after});
    if (!reply) return Unexpected(reply.error());
    // Nothing new for a second: refresh the head (entries trimmed away show up here).
    if (reply.value().is_nil()) return refresh_head(c);
    // [[stream, [[id, [field, value, ...]], ...]]]
    const RedisReply& streams = reply.value();
    if (streams.elements.empty() || streams.elements[0].elements.size() < 2) return {};
    const std::vector<RedisReply>& entries = streams.elements[0].elements[1].elements;
    for (const RedisReply& e : entries) {
        if (m_state.shutting_down()) return {};
        if (e.elements.size() < 2) {
            m_state.stop_loudly("the log returned a malformed entry");
            return storage("malformed");
        }
        const StreamEntry entry = read_stream_entry(e);
        const uint64_t applied = m_state.applied();
        if (Status s = check_entry_order(entry, applied); !s) return s;
        if (entry.version != applied + 1) {
            // Trimmed before this replica read them: jump to the snapshot, then read on from it
            // (the rest of this reply is older than the snapshot's version or read again).
            return jump_to_snapshot(c, applied,
                                    "the log entry of version " + std::to_string(entry.version) +
                                        " follows this replica's version " +
                                        std::to_string(applied) +
                                        ": the entries between were trimmed before it read them");
        }
        m_state.raise_log_version(entry.version);
        m_state.entry_waiting(entry.appended_ms);

        // Step: check and apply the entry at exactly the version it was appended for.
        if (Status s = apply_entry(entry, applied); !s) return s;
        record_applied(entry);
    }
    return {};
}

Status LogReader::refresh_head(RedisConnection& c) {
    auto head = read_log_head(c);
    if (!head) return Unexpected(head.error());
    m_state.raise_log_version(head.value());
    if (m_state.log_version() <= m_state.applied()) return {};
    // The head moved but XREAD found nothing after us: the entries are gone.
    const uint64_t applied = m_state.applied();
    auto held = holds_entry_after(c, applied);
    if (!held) return Unexpected(held.error());
    if (held.value()) return {};
    return jump_to_snapshot(c, applied,
                            "the log is at version " + std::to_string(m_state.log_version()) +
                                " but holds no entry after version " + std::to_string(applied) +
                                " (trimmed or deleted)");
}

LogReader::StreamEntry LogReader::read_stream_entry(const RedisReply& e) {
    StreamEntry entry{.id = e.elements[0].str};
    entry.has_version = parse_entry_version(entry.id, entry.version);
    const auto& fields = e.elements[1].elements;
    for (std::size_t i = 0; i + 1 < fields.size(); i += 2) {
        if (fields[i].str == "r") entry.record = &fields[i + 1].str;
        if (fields[i].str == "t")
            (void)std::from_chars(fields[i + 1].str.data(),
                                  fields[i + 1].str.data() + fields[i + 1].str.size(),
                                  entry.appended_ms);
    }
    return entry;
}

Status LogReader::check_entry_order(const StreamEntry& entry, uint64_t applied) {
    if (!entry.has_version || entry.record == nullptr) {
        m_state.stop_loudly("the log entry " + entry.id +
                            " is not a Strata entry (no version id or no "
                            "field 'r')");
        return storage("poisoned");
    }
    if (entry.version <= applied) {
        m_state.stop_loudly("the log entry of version " + std::to_string(entry.version) +
                            " comes after this replica's version " + std::to_string(applied) +
                            " in the stream (entries out of order)");
        return storage("out of order");
    }
    return {};
}

Status LogReader::apply_entry(const StreamEntry& entry, uint64_t applied) {
    auto decoded = decode_entry(*entry.record);
    if (!decoded || decoded.value().version != entry.version) {
        m_state.stop_loudly("poisoned log entry " + entry.id + ": " +
                            (decoded ? "it says version " + std::to_string(decoded.value().version)
                                     : decoded.error().message));
        return storage("poisoned");
    }
    // The count first: an entry of more edits than a batch may hold is refused before one is
    // decoded (a few bytes an edit could ask for gigabytes).
    const std::string_view payload = decoded.value().payload;
    if (const uint32_t count = durable::edit_count(payload); count > m_options.max_batch_edits) {
        m_state.stop_loudly("log entry " + entry.id + " holds " + std::to_string(count) +
                            " edits, more than a batch may hold (--max-batch-edits " +
                            std::to_string(m_options.max_batch_edits) + ")");
        return storage("too many edits");
    }
    auto batch = durable::decode_batch(payload);
    if (!batch) {
        m_state.stop_loudly("poisoned log entry " + entry.id + ": " + batch.error().describe());
        return storage("poisoned");
    }
    auto done = m_engine.apply(std::move(batch.value()), applied);
    if (!done) {
        m_state.stop_loudly("poisoned log entry " + entry.id + " does not apply at version " +
                            std::to_string(applied) + ": " + done.error().describe());
        return storage("poisoned");
    }
    return {};
}

void LogReader::record_applied(const StreamEntry& entry) {
    const uint64_t version = entry.version;
    m_state.applied_entry(version, entry.appended_ms);
    if (!m_state.joined() && version >= m_join_target) m_state.mark_joined();
    if (m_snapshots && m_options.snapshot_every > 0 && version % m_options.snapshot_every == 0 &&
        version > m_state.known_snapshot())
        m_snapshots->due();
}

Status LogReader::jump_to_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap) {
    if (Status s = load_snapshot(c, applied, gap); !s) return s;
    if (!m_state.joined() && m_state.applied() >= m_join_target) m_state.mark_joined();
    return {};
}

Result<uint64_t> LogReader::read_log_head(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    auto reply = c.eval(LOG_HEAD_SCRIPT, {url.stream, url.version_key()}, {});
    if (!reply) return Unexpected(reply.error());
    const RedisReply& r = reply.value();
    if (r.elements.size() != 2)
        return storage("the edit log's head script answered something unexpected");
    const RedisReply& key = r.elements[0];
    const RedisReply& newest = r.elements[1];
    uint64_t head = 0;
    if (!key.is_nil() && !parse_u64(key.str, head)) {
        m_state.stop_loudly("the key " + url.version_key() + " does not hold a version ('" +
                            key.str.substr(0, 40) + "')");
        return m_state.stopped_error();
    }
    if (Status s = m_state.check_not_behind(head); !s) return Unexpected(s.error());
    // The newest entry is always the head's: trimming removes only older ones.
    const std::string expected = head == 0 ? std::string() : entry_id(head);
    const std::string found = newest.is_nil() ? std::string() : newest.str;
    if (found != expected) {
        m_state.stop_loudly("the edit log was rewritten: " + url.version_key() + " says version " +
                            std::to_string(head) + " but the stream's newest entry is " +
                            (found.empty()
                                 ? std::string("missing (the stream was emptied or deleted)")
                                 : "'" + found.substr(0, 40) + "'"));
        return m_state.stopped_error();
    }
    return head;
}

Result<bool> LogReader::holds_entry_after(RedisConnection& c, uint64_t applied) {
    auto first =
        c.command({"XRANGE", m_options.url.stream, entry_id(applied + 1), "+", "COUNT", "1"});
    if (!first) return Unexpected(first.error());
    const RedisReply& r = first.value();
    uint64_t version = 0;
    return !r.elements.empty() && !r.elements[0].elements.empty() &&
           parse_entry_version(r.elements[0].elements[0].str, version) && version == applied + 1;
}

Status LogReader::load_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap) {
    const RedisUrl& url = m_options.url;
    // Step: the stored snapshot, version and bytes in one read (the script sets both at once).
    auto stored = c.command({"HMGET", url.snapshot_key(), "version", "bytes"});
    if (!stored) return Unexpected(stored.error());
    const RedisReply& r = stored.value();
    uint64_t snapshot = 0;
    if (r.elements.size() == 2 && !r.elements[0].is_nil())
        (void)parse_u64(r.elements[0].str, snapshot);
    m_state.know_snapshot(snapshot);
    if (snapshot <= applied) {
        // Only a newer snapshot bridges a gap; an older one never replaces anything.
        m_state.stop_loudly(
            gap + ", and the snapshot in " + url.snapshot_key() + " is " +
            (snapshot == 0 ? std::string("missing") : "at version " + std::to_string(snapshot)) +
            ", not newer than this replica's version " + std::to_string(applied) +
            ": nothing can bridge the gap (was the stream trimmed by hand?)");
        return storage("gap");
    }
    const std::string& bytes = r.elements[1].str;
    auto view = durable::open_snapshot(bytes);
    if (!view || view.value().version != snapshot) {
        m_state.stop_loudly("the snapshot in " + url.snapshot_key() + " is unusable: " +
                            (view ? "it holds version " + std::to_string(view.value().version) +
                                        ", the hash says " + std::to_string(snapshot)
                                  : view.error().message));
        return storage("bad snapshot");
    }
    // Step: the whole scene replaced in one swap (and written to the data directory first, when
    // there is one); on failure the old scene stays and the replica stops.
    auto replaced = m_options.store
                        ? m_options.store->replace_scene(bytes)
                        : m_engine.replace_with_snapshot(view.value().payload, snapshot);
    if (!replaced) {
        m_state.stop_loudly(
            "the snapshot of version " + std::to_string(snapshot) + " does not load" +
            (applied ? " in place of this replica's version " + std::to_string(applied)
                     : std::string()) +
            ": " + replaced.error().describe());
        return storage("bad snapshot");
    }
    m_state.loaded_snapshot(snapshot, applied > 0);
    if (applied == 0) {
        spdlog::info("edit log: loaded the snapshot of version {} ({} bytes) from {}", snapshot,
                     bytes.size(), url.snapshot_key());
    } else {
        spdlog::info(
            "edit log: {}; loaded the snapshot of version {} ({} bytes) from {} in place of "
            "version {} (built in {:.1f} ms, scene locked {:.3f} ms{}); following from version {}",
            gap, snapshot, bytes.size(), url.snapshot_key(), applied, replaced->load_ms,
            replaced->lock_ms, m_options.store ? ", written to the data directory" : "",
            snapshot + 1);
    }
    return {};
}

}  // namespace strata::replica

#include "server/replica/replica.h"

#include <algorithm>
#include <charconv>
#include <cstring>

#include <spdlog/spdlog.h>

#include "engine/durable/durable_store.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "server/replica/log_entry.h"
#include "server/replica/redis_connection.h"

namespace strata::replica {

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr milliseconds CONNECT_TIMEOUT{1000};
constexpr milliseconds READER_COMMAND_TIMEOUT{5000};  // above XREAD's BLOCK
constexpr milliseconds WRITER_COMMAND_TIMEOUT{2000};
constexpr const char* BLOCK_MS = "1000";
constexpr const char* READ_COUNT = "256";
constexpr milliseconds BACKOFF_FIRST{50};
constexpr milliseconds BACKOFF_MAX{2000};

// Appends ARGV[2] as version ARGV[1] + 1 only while the log's last version is ARGV[1]. Returns
// {1, new version} or {0, the log's version}. One script: Redis runs it atomically.
const std::string APPEND_SCRIPT = R"lua(
local head = tonumber(redis.call('GET', KEYS[2]) or '0')
if head ~= tonumber(ARGV[1]) then return {0, head} end
local v = head + 1
redis.call('XADD', KEYS[1], string.format('%d-0', v), 'v', string.format('%d', v), 't', ARGV[3], 'r', ARGV[2])
redis.call('SET', KEYS[2], string.format('%d', v))
return {1, v}
)lua";

// The log's version key and the id of its newest entry, read at once (the append script writes
// both at once): {version or nil, id or nil}.
const std::string LOG_HEAD_SCRIPT = R"lua(
local newest = redis.call('XREVRANGE', KEYS[1], '+', '-', 'COUNT', 1)
local id = false
if #newest > 0 then id = newest[1][1] end
return {redis.call('GET', KEYS[2]), id}
)lua";

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

int64_t unix_ms() {
    return std::chrono::duration_cast<milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

bool parse_u64(std::string_view s, uint64_t& out) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size();
}

/// "123-0" -> 123.
bool parse_entry_version(std::string_view id, uint64_t& v) {
    const std::size_t dash = id.find('-');
    return dash != std::string_view::npos && parse_u64(id.substr(0, dash), v);
}

Unexpected<Error> storage(std::string message) {
    return failure(ErrorCode::Storage, std::move(message));
}

/// What is left of the time until `deadline`; none once it has passed.
milliseconds time_left(Clock::time_point deadline) {
    return std::max(milliseconds(0),
                    std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
}

/// The answer to a write with If-Match `expected` when the edit log is at `head`.
Unexpected<Error> log_moved_on(uint64_t head, uint64_t expected) {
    return failure(
        ErrorCode::VersionMismatch,
        "the edit log is at version " + std::to_string(head) + ", not " + std::to_string(expected));
}

}  // namespace

Replica::Replica(const ReplicaOptions& options, Engine& engine)
    : m_options(options), m_engine(engine) {
    m_counters.log = options.url.describe();
}

std::unique_ptr<Replica> Replica::start(const ReplicaOptions& options, Engine& engine) {
    std::unique_ptr<Replica> r(new Replica(options, engine));
    const uint64_t version = engine.read([](const Scene& s) { return s.version(); });
    r->m_applied = version;
    r->m_log_version = version;
    r->m_reader = std::thread([p = r.get()] { p->reader_loop(); });
    if (options.snapshot_every > 0)
        r->m_snapshotter = std::thread([p = r.get()] { p->snapshot_loop(); });
    return r;
}

Replica::~Replica() {
    m_shutdown = true;
    { std::lock_guard lock(m_mutex); }
    m_cv.notify_all();
    {
        std::lock_guard lock(m_snapshot_mutex);
        m_snapshot_due = true;
    }
    m_snapshot_cv.notify_all();
    if (m_reader.joinable()) m_reader.join();
    if (m_snapshotter.joinable()) m_snapshotter.join();
}

bool Replica::sleep_for(milliseconds d) {
    std::unique_lock lock(m_mutex);
    m_cv.wait_for(lock, d, [&] { return m_shutdown.load(); });
    return !m_shutdown.load();
}

void Replica::stop_loudly(const std::string& why) {
    {
        std::lock_guard lock(m_mutex);
        if (m_stopped) return;
        m_stop_reason = why;
        m_stopped = true;
    }
    m_cv.notify_all();
    spdlog::critical(
        "replica stopped: {}. It applies nothing more from {} and answers 503 to writes and "
        "/readyz; reads show version {}. Fix the log, then restart it.",
        why, m_options.url.describe(), m_applied.load());
}

void Replica::mark_joined() {
    {
        std::lock_guard lock(m_mutex);
        m_joined = true;
    }
    m_cv.notify_all();
    spdlog::info("edit log {}: caught up at version {}; following", m_options.url.describe(),
                 m_applied.load());
}

void Replica::set_log_version(uint64_t v) {
    uint64_t cur = m_log_version.load();
    while (v > cur && !m_log_version.compare_exchange_weak(cur, v)) {
    }
}

// ---------------------------------------------------------------------------------------------
// The reader: the one path by which batches reach the engine.

void Replica::reader_loop() {
    std::unique_ptr<RedisConnection> conn;
    milliseconds backoff = BACKOFF_FIRST;
    bool had_connection = false;
    bool warned = false;
    while (!m_shutdown && !m_stopped) {
        if (!conn) {
            auto made =
                RedisConnection::connect(m_options.url, CONNECT_TIMEOUT, READER_COMMAND_TIMEOUT);
            if (!made) {
                if (!warned)
                    spdlog::warn(
                        "edit log: {}; retrying with backoff (writes answer 503 "
                        "meanwhile, reads serve version {})",
                        made.error().message, m_applied.load());
                warned = true;
                if (!sleep_for(backoff)) break;
                backoff = std::min(backoff * 2, BACKOFF_MAX);
                continue;
            }
            conn = std::move(made.value());
            if (Status s = on_connect(*conn); !s) {
                conn.reset();
                if (m_stopped) break;
                if (!sleep_for(backoff)) break;
                backoff = std::min(backoff * 2, BACKOFF_MAX);
                continue;
            }
            if (had_connection) {
                std::lock_guard lock(m_mutex);
                ++m_counters.reconnects;
            }
            if (warned || had_connection)
                spdlog::info("edit log {} reachable again at version {} (applied {})",
                             m_options.url.describe(), m_log_version.load(), m_applied.load());
            had_connection = true;
            warned = false;
            backoff = BACKOFF_FIRST;
            m_connected = true;
        }
        if (Status s = read_and_apply(*conn); !s) {
            if (m_stopped || m_shutdown) break;
            spdlog::warn("edit log: {}; reconnecting", s.error().message);
            conn.reset();
            m_connected = false;
            warned = true;
        }
    }
    m_connected = false;
}

Status Replica::on_connect(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    // Step: the log's head, and the snapshot an empty replica starts from.
    auto head = read_log_head(c);
    if (!head) return Unexpected(head.error());
    const uint64_t log_version = head.value();
    auto snap_version = c.command({"HGET", url.snapshot_key(), "version"});
    if (!snap_version) return Unexpected(snap_version.error());
    uint64_t snapshot = 0;
    if (!snap_version.value().is_nil()) (void)parse_u64(snap_version.value().str, snapshot);
    m_known_snapshot = std::max(m_known_snapshot.load(), snapshot);

    const uint64_t applied = m_applied.load();
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
    set_log_version(log_version);
    if (!m_joined) {
        m_join_target = log_version;
        if (m_applied.load() >= m_join_target) mark_joined();
    }
    return {};
}

Status Replica::read_and_apply(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    const std::string after = entry_id(m_applied.load());
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
        if (m_shutdown) return {};
        if (e.elements.size() < 2) {
            stop_loudly("the log returned a malformed entry");
            return storage("malformed");
        }
        const StreamEntry entry = read_stream_entry(e);
        const uint64_t applied = m_applied.load();
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
        set_log_version(entry.version);
        if (m_lag_since_ms.load() == 0)
            m_lag_since_ms = entry.appended_ms ? entry.appended_ms : unix_ms();

        // Step: check and apply the entry at exactly the version it was appended for.
        if (Status s = apply_entry(entry, applied); !s) return s;
        record_applied(entry);
    }
    return {};
}

Status Replica::refresh_head(RedisConnection& c) {
    auto head = read_log_head(c);
    if (!head) return Unexpected(head.error());
    set_log_version(head.value());
    if (m_log_version.load() <= m_applied.load()) return {};
    // The head moved but XREAD found nothing after us: the entries are gone.
    const uint64_t applied = m_applied.load();
    auto held = holds_entry_after(c, applied);
    if (!held) return Unexpected(held.error());
    if (held.value()) return {};
    return jump_to_snapshot(c, applied,
                            "the log is at version " + std::to_string(m_log_version.load()) +
                                " but holds no entry after version " + std::to_string(applied) +
                                " (trimmed or deleted)");
}

Replica::StreamEntry Replica::read_stream_entry(const RedisReply& e) {
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

Status Replica::check_entry_order(const StreamEntry& entry, uint64_t applied) {
    if (!entry.has_version || entry.record == nullptr) {
        stop_loudly("the log entry " + entry.id +
                    " is not a Strata entry (no version id or no "
                    "field 'r')");
        return storage("poisoned");
    }
    if (entry.version <= applied) {
        stop_loudly("the log entry of version " + std::to_string(entry.version) +
                    " comes after this replica's version " + std::to_string(applied) +
                    " in the stream (entries out of order)");
        return storage("out of order");
    }
    return {};
}

Status Replica::apply_entry(const StreamEntry& entry, uint64_t applied) {
    auto decoded = decode_entry(*entry.record);
    if (!decoded || decoded.value().version != entry.version) {
        stop_loudly("poisoned log entry " + entry.id + ": " +
                    (decoded ? "it says version " + std::to_string(decoded.value().version)
                             : decoded.error().message));
        return storage("poisoned");
    }
    // The count first: an entry of more edits than a batch may hold is refused before one is
    // decoded (a few bytes an edit could ask for gigabytes).
    const std::string_view payload = decoded.value().payload;
    uint32_t count = 0;
    if (payload.size() >= sizeof count) std::memcpy(&count, payload.data(), sizeof count);
    if (count > m_options.max_batch_edits) {
        stop_loudly("log entry " + entry.id + " holds " + std::to_string(count) +
                    " edits, more than a batch may hold (--max-batch-edits " +
                    std::to_string(m_options.max_batch_edits) + ")");
        return storage("too many edits");
    }
    auto batch = durable::decode_batch(payload);
    if (!batch) {
        stop_loudly("poisoned log entry " + entry.id + ": " + batch.error().describe());
        return storage("poisoned");
    }
    auto done = m_engine.apply(std::move(batch.value()), applied);
    if (!done) {
        stop_loudly("poisoned log entry " + entry.id + " does not apply at version " +
                    std::to_string(applied) + ": " + done.error().describe());
        return storage("poisoned");
    }
    return {};
}

void Replica::record_applied(const StreamEntry& entry) {
    const uint64_t version = entry.version;
    {
        std::lock_guard lock(m_mutex);
        m_applied = version;
        ++m_counters.entries_applied;
    }
    m_cv.notify_all();
    if (version >= m_log_version.load()) {
        m_lag_since_ms = 0;
    } else {
        m_lag_since_ms = entry.appended_ms ? entry.appended_ms : m_lag_since_ms.load();
    }
    if (!m_joined && version >= m_join_target) mark_joined();
    if (m_options.snapshot_every > 0 && version % m_options.snapshot_every == 0 &&
        version > m_known_snapshot.load()) {
        {
            std::lock_guard lock(m_snapshot_mutex);
            m_snapshot_due = true;
        }
        m_snapshot_cv.notify_one();
    }
}

Status Replica::jump_to_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap) {
    if (Status s = load_snapshot(c, applied, gap); !s) return s;
    if (!m_joined && m_applied.load() >= m_join_target) mark_joined();
    return {};
}

Result<uint64_t> Replica::read_log_head(RedisConnection& c) {
    const RedisUrl& url = m_options.url;
    auto reply = c.eval(LOG_HEAD_SCRIPT, {url.stream, url.version_key()}, {});
    if (!reply) return Unexpected(reply.error());
    const RedisReply& r = reply.value();
    if (r.elements.size() != 2) return storage("the edit log's head script answered something unexpected");
    const RedisReply& key = r.elements[0];
    const RedisReply& newest = r.elements[1];
    uint64_t head = 0;
    if (!key.is_nil() && !parse_u64(key.str, head)) {
        stop_loudly("the key " + url.version_key() + " does not hold a version ('" +
                    key.str.substr(0, 40) + "')");
        return stopped_error();
    }
    if (Status s = check_not_behind(head); !s) return Unexpected(s.error());
    // The newest entry is always the head's: trimming removes only older ones.
    const std::string expected = head == 0 ? std::string() : entry_id(head);
    const std::string found = newest.is_nil() ? std::string() : newest.str;
    if (found != expected) {
        stop_loudly("the edit log was rewritten: " + url.version_key() + " says version " +
                    std::to_string(head) + " but the stream's newest entry is " +
                    (found.empty() ? std::string("missing (the stream was emptied or deleted)")
                                   : "'" + found.substr(0, 40) + "'"));
        return stopped_error();
    }
    return head;
}

Status Replica::check_not_behind(uint64_t head) {
    const uint64_t applied = m_applied.load();
    if (head >= applied) return {};
    stop_loudly("the edit log ends at version " + std::to_string(head) +
                ", behind this replica's version " + std::to_string(applied) +
                " (was Redis reset, or did it lose acknowledged entries?)");
    return stopped_error();
}

Result<bool> Replica::holds_entry_after(RedisConnection& c, uint64_t applied) {
    auto first = c.command(
        {"XRANGE", m_options.url.stream, entry_id(applied + 1), "+", "COUNT", "1"});
    if (!first) return Unexpected(first.error());
    const RedisReply& r = first.value();
    uint64_t version = 0;
    return !r.elements.empty() && !r.elements[0].elements.empty() &&
           parse_entry_version(r.elements[0].elements[0].str, version) && version == applied + 1;
}

Status Replica::load_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap) {
    const RedisUrl& url = m_options.url;
    // Step: the stored snapshot, version and bytes in one read (the script sets both at once).
    auto stored = c.command({"HMGET", url.snapshot_key(), "version", "bytes"});
    if (!stored) return Unexpected(stored.error());
    const RedisReply& r = stored.value();
    uint64_t snapshot = 0;
    if (r.elements.size() == 2 && !r.elements[0].is_nil())
        (void)parse_u64(r.elements[0].str, snapshot);
    m_known_snapshot = std::max(m_known_snapshot.load(), snapshot);
    if (snapshot <= applied) {
        // Only a newer snapshot bridges a gap; an older one never replaces anything.
        stop_loudly(gap + ", and the snapshot in " + url.snapshot_key() + " is " +
                    (snapshot == 0 ? std::string("missing")
                                   : "at version " + std::to_string(snapshot)) +
                    ", not newer than this replica's version " + std::to_string(applied) +
                    ": nothing can bridge the gap (was the stream trimmed by hand?)");
        return storage("gap");
    }
    const std::string& bytes = r.elements[1].str;
    auto view = durable::open_snapshot(bytes);
    if (!view || view.value().version != snapshot) {
        stop_loudly("the snapshot in " + url.snapshot_key() + " is unusable: " +
                    (view ? "it holds version " + std::to_string(view.value().version) +
                                ", the hash says " + std::to_string(snapshot)
                          : view.error().message));
        return storage("bad snapshot");
    }
    // Step: the whole scene replaced in one swap (and written to the data directory first, when
    // there is one); on failure the old scene stays and the replica stops.
    auto replaced = m_options.store ? m_options.store->replace_scene(bytes)
                                    : m_engine.replace_with_snapshot(view.value().payload, snapshot);
    if (!replaced) {
        stop_loudly("the snapshot of version " + std::to_string(snapshot) + " does not load" +
                    (applied ? " in place of this replica's version " + std::to_string(applied)
                             : std::string()) +
                    ": " + replaced.error().describe());
        return storage("bad snapshot");
    }
    {
        std::lock_guard lock(m_mutex);
        m_applied = snapshot;
        m_counters.snapshot_loaded_version = snapshot;
        if (applied > 0) ++m_counters.snapshot_jumps;
    }
    m_cv.notify_all();
    set_log_version(snapshot);
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

// ---------------------------------------------------------------------------------------------
// The write path: validate, append conditionally, wait for the reader.

RedisConnection* Replica::writer(Error& error) {
    if (m_writer && !m_writer->broken()) return m_writer.get();
    m_writer.reset();
    const auto now = Clock::now();
    if (now < m_writer_retry_at) {
        error = make_error(ErrorCode::Storage, "the edit log " + m_options.url.describe() +
                                                   " is unreachable (retrying)");
        return nullptr;
    }
    auto made = RedisConnection::connect(m_options.url, CONNECT_TIMEOUT, WRITER_COMMAND_TIMEOUT);
    if (!made) {
        m_writer_backoff = m_writer_backoff.count() == 0
                               ? BACKOFF_FIRST
                               : std::min(m_writer_backoff * 2, BACKOFF_MAX);
        m_writer_retry_at = now + m_writer_backoff;
        error =
            make_error(ErrorCode::Storage, "the edit log is unreachable: " + made.error().message);
        return nullptr;
    }
    m_writer_backoff = milliseconds(0);
    m_writer = std::move(made.value());
    return m_writer.get();
}

Result<ApplyResult> Replica::append(EditBatch&& batch, std::optional<uint64_t> expected) {
    const auto deadline = Clock::now() + m_options.write_timeout;
    if (Status joined = wait_joined(deadline); !joined) return Unexpected(joined.error());

    // The entry is encoded once; each attempt only restamps its version.
    const std::size_t count = batch.edits.size();
    std::string entry = encode_entry(batch, 0);
    batch = {};
    for (;;) {
        // Step: every try within the write deadline; a stopped replica or a shutdown ends it.
        if (m_stopped) return stopped_error();
        if (m_shutdown) return storage("the server is shutting down");
        if (Clock::now() >= deadline)
            return storage("the batch could not be appended to the edit log within " +
                           std::to_string(m_options.write_timeout.count()) + " ms");
        // Step: the version to validate at. A client that saw a newer version (If-Match) than
        // this replica has applied waits for it first.
        auto base = validation_base(expected, deadline);
        if (!base) return Unexpected(base.error());
        // Step: validate against the local scene at `base`.
        auto valid = validate_at(entry, base.value(), expected, deadline);
        if (!valid) return Unexpected(valid.error());
        if (!valid.value()) continue;
        // Step: append only while the log's head is still `base`.
        auto answer = append_at(entry, base.value());
        if (!answer) return Unexpected(answer.error());
        if (answer->appended) return await_appended(answer->head, count, deadline);
        // Step: the log moved on. With If-Match that is the client's answer; without, catch
        // up and try again.
        if (Status s = catch_up_after_conflict(answer->head, expected, deadline); !s)
            return Unexpected(s.error());
    }
}

Unexpected<Error> Replica::stopped_error() const {
    std::lock_guard lock(m_mutex);
    return storage("this replica has stopped following the edit log: " + m_stop_reason);
}

Status Replica::wait_joined(Clock::time_point deadline) {
    if (m_stopped) return stopped_error();
    {
        std::unique_lock lock(m_mutex);
        m_cv.wait_until(lock, deadline, [&] { return m_joined || m_stopped || m_shutdown; });
    }
    if (m_stopped) return stopped_error();
    if (!m_joined)
        return storage("this replica has not caught up with the edit log " +
                       m_options.url.describe() + " yet (is Redis reachable?)");
    return {};
}

Result<uint64_t> Replica::validation_base(std::optional<uint64_t> expected,
                                          Clock::time_point deadline) {
    if (expected && m_applied.load() < *expected && !wait_applied(*expected, time_left(deadline))) {
        if (m_stopped) return stopped_error();
        return storage("this replica is at version " + std::to_string(m_applied.load()) +
                       ", behind the If-Match version " + std::to_string(*expected) +
                       ", and did not catch up in time");
    }
    const uint64_t base = m_applied.load();
    if (expected && base != *expected)
        return failure(ErrorCode::VersionMismatch, "the scene is at version " +
                                                       std::to_string(base) + ", not " +
                                                       std::to_string(*expected));
    return base;
}

Result<bool> Replica::validate_at(const std::string& entry, uint64_t base,
                                  std::optional<uint64_t> expected, Clock::time_point deadline) {
    auto copy = durable::decode_batch(std::string_view(entry).substr(durable::RECORD_HEADER_BYTES));
    if (!copy) return Unexpected(copy.error());
    Status ok = m_engine.validate(std::move(copy.value()), base);
    if (ok) return true;
    if (ok.error().code != ErrorCode::VersionMismatch) {
        // Refused at `base`: maybe only because this replica has not applied what the log
        // holds yet (a client writing on one replica, then on another). The answer stands
        // only against the log's head.
        auto head = log_head();
        if (!head) return Unexpected(head.error());
        if (Status s = check_not_behind(head.value()); !s) return Unexpected(s.error());
        if (head.value() <= base) return Unexpected(ok.error());
        set_log_version(head.value());
        if (expected) return log_moved_on(head.value(), *expected);
        if (!wait_applied(head.value(), time_left(deadline))) {
            if (m_stopped) return stopped_error();
            return storage("this replica did not catch up with the edit log (version " +
                           std::to_string(head.value()) + ") in time to validate");
        }
        return false;
    }
    // The reader applied an entry meanwhile: validate again at the new version.
    if (Clock::now() >= deadline)
        return storage("the scene kept moving: the batch could not be validated within " +
                       std::to_string(m_options.write_timeout.count()) + " ms");
    std::this_thread::yield();
    return false;
}

Result<Replica::AppendAnswer> Replica::append_at(const std::string& entry, uint64_t base) {
    const std::string stamped = restamp_entry(entry, base + 1);
    const std::string base_text = std::to_string(base);
    const std::string now_text = std::to_string(unix_ms());
    Result<RedisReply> reply = [&]() -> Result<RedisReply> {
        std::lock_guard lock(m_writer_mutex);
        Error error;
        RedisConnection* c = writer(error);
        if (!c) return Unexpected(error);
        return c->eval(APPEND_SCRIPT, {m_options.url.stream, m_options.url.version_key()},
                       {base_text, stamped, now_text});
    }();
    if (!reply) return Unexpected(reply.error());
    const RedisReply& r = reply.value();
    if (r.elements.size() != 2 || r.elements[1].integer < 0)
        return storage("the edit log's append script answered something unexpected");
    const AppendAnswer answer{r.elements[0].integer == 1, uint64_t(r.elements[1].integer)};
    // Refused at a head behind this replica: the log lost what this replica applied.
    if (!answer.appended) {
        if (Status s = check_not_behind(answer.head); !s) return Unexpected(s.error());
    }
    return answer;
}

Result<ApplyResult> Replica::await_appended(uint64_t version, std::size_t count,
                                            Clock::time_point deadline) {
    {
        std::lock_guard lock(m_mutex);
        ++m_counters.appends;
    }
    if (!wait_applied(version, time_left(deadline))) {
        if (m_stopped) return stopped_error();
        return storage("the batch was appended to the edit log as version " +
                       std::to_string(version) +
                       " but this replica has not applied it "
                       "in time (it will; read with min_version=" +
                       std::to_string(version) + ")");
    }
    return ApplyResult{version, count};
}

Status Replica::catch_up_after_conflict(uint64_t head, std::optional<uint64_t> expected,
                                        Clock::time_point deadline) {
    {
        std::lock_guard lock(m_mutex);
        ++m_counters.append_conflicts;
    }
    set_log_version(head);
    if (expected) return log_moved_on(head, *expected);
    if (!wait_applied(head, time_left(deadline))) {
        if (m_stopped) return stopped_error();
        return storage("the edit log kept moving: the batch could not be appended within " +
                       std::to_string(m_options.write_timeout.count()) + " ms");
    }
    return {};
}

Result<uint64_t> Replica::log_head() {
    std::lock_guard lock(m_writer_mutex);
    Error error;
    RedisConnection* c = writer(error);
    if (!c) return Unexpected(error);
    auto head = c->command({"GET", m_options.url.version_key()});
    if (!head) return Unexpected(head.error());
    uint64_t v = 0;
    if (!head.value().is_nil() && !parse_u64(head.value().str, v))
        return storage("the key " + m_options.url.version_key() + " does not hold a version");
    return v;
}

bool Replica::wait_applied(uint64_t version, milliseconds timeout) {
    std::unique_lock lock(m_mutex);
    return m_cv.wait_for(lock, timeout, [&] {
        return m_applied.load() >= version || m_stopped || m_shutdown;
    }) && m_applied.load() >= version;
}

ReplicaStatus Replica::status() const {
    ReplicaStatus s;
    {
        std::lock_guard lock(m_mutex);
        s = m_counters;
        s.stop_reason = m_stop_reason;
    }
    s.connected = m_connected;
    s.joined = m_joined;
    s.stopped = m_stopped;
    s.applied_version = m_applied;
    s.log_version = std::max(m_log_version.load(), s.applied_version);
    s.lag_entries = s.log_version - s.applied_version;
    const int64_t since = m_lag_since_ms.load();
    s.lag_seconds =
        s.lag_entries > 0 && since > 0 ? std::max<int64_t>(0, unix_ms() - since) / 1e3 : 0.0;
    s.snapshot_version = std::max(s.snapshot_version, m_known_snapshot.load());
    return s;
}

// ---------------------------------------------------------------------------------------------
// Snapshots in Redis, and trimming.

void Replica::snapshot_loop() {
    for (;;) {
        {
            std::unique_lock lock(m_snapshot_mutex);
            m_snapshot_cv.wait(lock, [&] { return m_snapshot_due || m_shutdown; });
            m_snapshot_due = false;
        }
        if (m_shutdown) return;
        if (Status s = write_snapshot(); !s)
            spdlog::warn("edit log snapshot not stored (the log keeps its entries): {}",
                         s.error().message);
    }
}

Status Replica::write_snapshot() {
    const RedisUrl& url = m_options.url;
    auto made = RedisConnection::connect(url, CONNECT_TIMEOUT, milliseconds(30000));
    if (!made) return Unexpected(made.error());
    RedisConnection& c = *made.value();
    // Step: another replica may have stored this version already.
    auto stored = c.command({"HGET", url.snapshot_key(), "version"});
    if (!stored) return Unexpected(stored.error());
    uint64_t have = 0;
    if (!stored.value().is_nil()) (void)parse_u64(stored.value().str, have);
    m_known_snapshot = std::max(m_known_snapshot.load(), have);
    SceneImage image = m_engine.read([](const Scene& s) { return s.image(); });
    if (image.version <= have) return {};
    // Step: encoded outside the scene lock, stored and trimmed in one script.
    const std::string bytes = durable::encode_snapshot(image.to_batch(), image.version);
    const uint64_t version = image.version;
    image = {};
    auto reply =
        c.eval(SNAPSHOT_SCRIPT, {url.snapshot_key(), url.stream}, {std::to_string(version), bytes});
    if (!reply) return Unexpected(reply.error());
    const RedisReply& r = reply.value();
    if (r.elements.size() != 3) return storage("the snapshot script answered something unexpected");
    m_known_snapshot = std::max(m_known_snapshot.load(), uint64_t(r.elements[1].integer));
    if (r.elements[0].integer == 1) {
        std::lock_guard lock(m_mutex);
        ++m_counters.snapshots_written;
        m_counters.entries_trimmed += uint64_t(r.elements[2].integer);
        spdlog::info(
            "edit log: stored the snapshot of version {} ({} bytes) in {}; trimmed {} "
            "entries",
            version, bytes.size(), url.snapshot_key(), r.elements[2].integer);
    }
    return {};
}

}  // namespace strata::replica

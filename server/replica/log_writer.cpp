#include "server/replica/log_writer.h"

#include <thread>

#include "engine/core/timer.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "server/replica/log_entry.h"
#include "server/replica/redis_connection.h"

namespace strata::replica {

namespace {

constexpr milliseconds WRITER_COMMAND_TIMEOUT{2000};

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

/// The answer to a write with If-Match `expected` when the edit log is at `head`.
Unexpected<Error> log_moved_on(uint64_t head, uint64_t expected) {
    return failure(
        ErrorCode::VersionMismatch,
        "the edit log is at version " + std::to_string(head) + ", not " + std::to_string(expected));
}

}  // namespace

LogWriter::LogWriter(const ReplicaOptions& options, Engine& engine, ReplicaState& state)
    : m_options(options), m_engine(engine), m_state(state) {}

LogWriter::~LogWriter() = default;

RedisConnection* LogWriter::writer(Error& error) {
    if (m_writer && !m_writer->broken()) return m_writer.get();
    m_writer.reset();
    const auto now = Clock::now();
    if (now < m_writer_retry_at) {
        error = make_error(ErrorCode::Storage,
                           "the edit log " + m_state.log() + " is unreachable (retrying)");
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

Result<ApplyResult> LogWriter::append(EditBatch&& batch, std::optional<uint64_t> expected) {
    const auto deadline = Clock::now() + m_options.write_timeout;
    if (Status joined = m_state.wait_joined(deadline); !joined) return Unexpected(joined.error());

    // The entry is encoded once; each attempt only restamps its version. Its time is the
    // writer's, so every replica's history shows the same one.
    const std::size_t count = batch.edits.size();
    if (batch.info.time_ms == 0) batch.info.time_ms = unix_ms();
    std::string entry = encode_entry(batch, 0);
    batch = {};
    for (;;) {
        // Step: every try within the write deadline; a stopped replica or a shutdown ends it.
        if (m_state.stopped()) return m_state.stopped_error();
        if (m_state.shutting_down()) return storage("the server is shutting down");
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

Result<uint64_t> LogWriter::validation_base(std::optional<uint64_t> expected,
                                            Clock::time_point deadline) {
    if (expected && m_state.applied() < *expected &&
        !m_state.wait_applied(*expected, time_left(deadline))) {
        if (m_state.stopped()) return m_state.stopped_error();
        return storage("this replica is at version " + std::to_string(m_state.applied()) +
                       ", behind the If-Match version " + std::to_string(*expected) +
                       ", and did not catch up in time");
    }
    const uint64_t base = m_state.applied();
    if (expected && base != *expected)
        return failure(ErrorCode::VersionMismatch, "the scene is at version " +
                                                       std::to_string(base) + ", not " +
                                                       std::to_string(*expected));
    return base;
}

Result<bool> LogWriter::validate_at(const std::string& entry, uint64_t base,
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
        if (Status s = m_state.check_not_behind(head.value()); !s) return Unexpected(s.error());
        if (head.value() <= base) return Unexpected(ok.error());
        m_state.raise_log_version(head.value());
        if (expected) return log_moved_on(head.value(), *expected);
        if (!m_state.wait_applied(head.value(), time_left(deadline))) {
            if (m_state.stopped()) return m_state.stopped_error();
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

Result<LogWriter::AppendAnswer> LogWriter::append_at(const std::string& entry, uint64_t base) {
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
        if (Status s = m_state.check_not_behind(answer.head); !s) return Unexpected(s.error());
    }
    return answer;
}

Result<ApplyResult> LogWriter::await_appended(uint64_t version, std::size_t count,
                                              Clock::time_point deadline) {
    m_state.count(&ReplicaStatus::appends);
    if (!m_state.wait_applied(version, time_left(deadline))) {
        if (m_state.stopped()) return m_state.stopped_error();
        return storage("the batch was appended to the edit log as version " +
                       std::to_string(version) +
                       " but this replica has not applied it "
                       "in time (it will; read with min_version=" +
                       std::to_string(version) + ")");
    }
    return ApplyResult{version, count};
}

Status LogWriter::catch_up_after_conflict(uint64_t head, std::optional<uint64_t> expected,
                                          Clock::time_point deadline) {
    m_state.count(&ReplicaStatus::append_conflicts);
    m_state.raise_log_version(head);
    if (expected) return log_moved_on(head, *expected);
    if (!m_state.wait_applied(head, time_left(deadline))) {
        if (m_state.stopped()) return m_state.stopped_error();
        return storage("the edit log kept moving: the batch could not be appended within " +
                       std::to_string(m_options.write_timeout.count()) + " ms");
    }
    return {};
}

Result<uint64_t> LogWriter::log_head() {
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

}  // namespace strata::replica

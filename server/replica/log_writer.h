#pragma once
// The replica's write path (replica.h, "One writer path"): validates a batch against the local
// scene at the applied version V, appends it with a script that succeeds only while the log's
// last version is still V, and waits until the reader has applied it; conflicts are retried
// within the write deadline (or, with If-Match, are the client's answer).

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "engine/engine.h"
#include "server/replica/replica.h"
#include "server/replica/replica_state.h"

namespace strata::replica {

class RedisConnection;

class LogWriter {
public:
    LogWriter(const ReplicaOptions& options, Engine& engine, ReplicaState& state);
    ~LogWriter();

    /// Replica::append. Thread-safe.
    Result<ApplyResult> append(EditBatch&& batch, std::optional<uint64_t> expected);

private:
    /// What the conditional append answered.
    struct AppendAnswer {
        bool appended = false;  ///< the log's head was still the base: the entry is in
        uint64_t head = 0;      ///< the entry's version once appended, else the log's version
    };

    /// The applied version to validate a write at; with `expected` (If-Match), waits for it
    /// first, and any other version is a VersionMismatch.
    Result<uint64_t> validation_base(std::optional<uint64_t> expected, Clock::time_point deadline);
    /// Validates the batch of `entry` against the local scene at `base`: true when it holds,
    /// false to try again at a newer version the replica has applied since; an error when it
    /// is refused against the log's head too, or time ran out.
    Result<bool> validate_at(const std::string& entry, uint64_t base,
                             std::optional<uint64_t> expected, Clock::time_point deadline);
    /// Appends `entry` as version `base` + 1 only while the log's head is still `base`.
    Result<AppendAnswer> append_at(const std::string& entry, uint64_t base);
    /// Counts the append of `version` (`count` edits) and waits until `deadline` for the reader
    /// to apply it.
    Result<ApplyResult> await_appended(uint64_t version, std::size_t count,
                                       Clock::time_point deadline);
    /// Counts an append refused because the log is at `head`. With `expected` (If-Match) that
    /// is the client's answer, a VersionMismatch; without, waits for the reader to catch up
    /// with `head` so that the write can try again.
    Status catch_up_after_conflict(uint64_t head, std::optional<uint64_t> expected,
                                   Clock::time_point deadline);
    /// The log's last version, read on the writer connection.
    Result<uint64_t> log_head();
    /// The writer connection, made on demand; null (and `error`) while Redis is unreachable.
    RedisConnection* writer(Error& error);

    const ReplicaOptions& m_options;
    Engine& m_engine;
    ReplicaState& m_state;
    std::mutex m_writer_mutex;
    std::unique_ptr<RedisConnection> m_writer;
    Clock::time_point m_writer_retry_at{};
    milliseconds m_writer_backoff{0};
};

}  // namespace strata::replica

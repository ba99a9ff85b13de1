#pragma once
// The replica's snapshotter (replica.h, "Snapshots and trimming"): on its own thread, stores a
// snapshot of the scene in the hash `<stream>:snapshot` when the reader applied a version due
// one, and trims the stream below the snapshot it replaced.

#include <condition_variable>
#include <mutex>
#include <thread>

#include "engine/engine.h"
#include "server/replica/redis_url.h"
#include "server/replica/replica_state.h"

namespace strata::replica {

class SnapshotWriter {
public:
    SnapshotWriter(const RedisUrl& url, Engine& engine, ReplicaState& state)
        : m_url(url), m_engine(engine), m_state(state) {}
    ~SnapshotWriter() { stop(); }

    void start();
    /// A version due a snapshot was applied. Thread-safe.
    void due();
    /// Waits for the thread (the snapshot in progress finishes). Idempotent.
    void stop();

private:
    void loop();
    Status write();

    const RedisUrl& m_url;
    Engine& m_engine;
    ReplicaState& m_state;
    std::mutex m_mutex;
    std::condition_variable m_cv;
    bool m_due = false;
    bool m_stopping = false;
    std::thread m_thread;
};

}  // namespace strata::replica

#include "server/replica/replica.h"

#include "server/replica/log_reader.h"
#include "server/replica/log_writer.h"
#include "server/replica/replica_state.h"
#include "server/replica/snapshot_writer.h"

namespace strata::replica {

Replica::Replica(const ReplicaOptions& options, Engine& engine) : m_options(options) {
    const uint64_t version = engine.read([](const Scene& s) { return s.version(); });
    m_state = std::make_unique<ReplicaState>(m_options.url.describe(), version);
    if (m_options.snapshot_every > 0)
        m_snapshots = std::make_unique<SnapshotWriter>(m_options.url, engine, *m_state);
    m_writer = std::make_unique<LogWriter>(m_options, engine, *m_state);
    m_reader = std::make_unique<LogReader>(m_options, engine, *m_state, m_snapshots.get());
}

std::unique_ptr<Replica> Replica::start(const ReplicaOptions& options, Engine& engine) {
    std::unique_ptr<Replica> r(new Replica(options, engine));
    r->m_reader->start();
    if (r->m_snapshots) r->m_snapshots->start();
    return r;
}

Replica::~Replica() {
    m_state->shut_down();
    m_reader->join();
    if (m_snapshots) m_snapshots->stop();
}

void Replica::stop() {
    m_state->shut_down();
}

Result<ApplyResult> Replica::append(EditBatch&& batch, std::optional<uint64_t> expected) {
    return m_writer->append(std::move(batch), expected);
}

uint64_t Replica::applied_version() const {
    return m_state->applied();
}

ReplicaStatus Replica::status() const {
    return m_state->status();
}

bool Replica::ready() const {
    return m_state->joined() && !m_state->stopped();
}

}  // namespace strata::replica

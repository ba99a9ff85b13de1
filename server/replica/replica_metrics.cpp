#include "server/replica/replica_metrics.h"

#include <cstdio>

namespace strata::replica {

namespace {

struct ReplicaMetricSpec {
    const char* name;
    const char* type;
    const char* help;
    double (*value)(const ReplicaStatus&);
};

// One row per metric: name, type, help and how to read it.
constexpr ReplicaMetricSpec REPLICA_METRICS[] = {
    {"strata_replica_applied_version", "gauge", "Scene version this replica has applied.",
     [](const ReplicaStatus& s) { return double(s.applied_version); }},
    {"strata_replica_log_version", "gauge", "Newest version this replica knows the log has.",
     [](const ReplicaStatus& s) { return double(s.log_version); }},
    {"strata_replica_lag_entries", "gauge", "Log entries this replica has not applied yet.",
     [](const ReplicaStatus& s) { return double(s.lag_entries); }},
    {"strata_replica_lag_seconds", "gauge",
     "How long the oldest unapplied log entry has waited (0 when caught up).",
     [](const ReplicaStatus& s) { return s.lag_seconds; }},
    {"strata_replica_connected", "gauge", "1 while the reader holds a connection to Redis.",
     [](const ReplicaStatus& s) { return s.connected ? 1.0 : 0.0; }},
    {"strata_replica_stopped", "gauge",
     "1 once the replica stopped following the log (a poisoned entry, a gap); see /readyz.",
     [](const ReplicaStatus& s) { return s.stopped ? 1.0 : 0.0; }},
    {"strata_replica_entries_applied_total", "counter", "Log entries applied by this replica.",
     [](const ReplicaStatus& s) { return double(s.entries_applied); }},
    {"strata_replica_appends_total", "counter", "Batches this replica appended to the log.",
     [](const ReplicaStatus& s) { return double(s.appends); }},
    {"strata_replica_append_conflicts_total", "counter",
     "Appends refused because the log had moved past the validated version.",
     [](const ReplicaStatus& s) { return double(s.append_conflicts); }},
    {"strata_replica_reconnects_total", "counter", "Reader reconnections to Redis.",
     [](const ReplicaStatus& s) { return double(s.reconnects); }},
    {"strata_replica_snapshots_written_total", "counter", "Snapshots this replica stored in Redis.",
     [](const ReplicaStatus& s) { return double(s.snapshots_written); }},
    {"strata_replica_snapshot_version", "gauge", "Newest snapshot version known in Redis.",
     [](const ReplicaStatus& s) { return double(s.last_snapshot_version); }},
    {"strata_replica_snapshot_jumps_total", "counter",
     "Times this replica replaced its scene with a newer Redis snapshot because the log entries "
     "after its version had been trimmed.",
     [](const ReplicaStatus& s) { return double(s.snapshot_jumps); }},
};

}  // namespace

void write_replica_metrics(std::string& out, const ReplicaStatus& s) {
    char value[64];
    for (const ReplicaMetricSpec& m : REPLICA_METRICS) {
        out += std::string("# HELP ") + m.name + ' ' + m.help + '\n';
        out += std::string("# TYPE ") + m.name + ' ' + m.type + '\n';
        std::snprintf(value, sizeof value, "%.17g", m.value(s));
        out += std::string(m.name) + ' ' + value + '\n';
    }
}

}  // namespace strata::replica

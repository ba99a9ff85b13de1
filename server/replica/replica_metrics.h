#pragma once
// The replica's numbers in Prometheus text (GET /metrics, with --log).

#include <string>

#include "server/replica/replica.h"

namespace strata::replica {

/// Appends every strata_replica_* metric of `s` to `out`.
void write_replica_metrics(std::string& out, const ReplicaStatus& s);

}  // namespace strata::replica

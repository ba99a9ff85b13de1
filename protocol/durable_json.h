#pragma once
// The data directory's numbers as JSON: the "durability" member of GET /v1/stats.

#include "engine/durable/durable_stats.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// Every DURABLE_COUNTERS entry, the fsync mode, the directory, the journal's failure (if any)
/// and the fsync latency histogram (`le` bounds in seconds, counts per bucket, not cumulative).
Json durable_stats_to_json(const durable::DurableStats& s);

/// The Prometheus name of a durable number: strata_durable_<name> in base units (milliseconds
/// become `_seconds`), `_total` for cumulative ones.
std::string durable_metric_name(const durable::DurableCounterSpec& spec);
/// Its value in the Prometheus name's unit.
double durable_metric_value(const durable::DurableCounterSpec& spec,
                            const durable::DurableStats& s);

}  // namespace strata::protocol

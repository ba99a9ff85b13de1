#pragma once
// The data directory's numbers as JSON: the "durability" member of GET /v1/stats.

#include "engine/durable/durable_stats.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// Every DURABLE_COUNTERS entry, the fsync mode, the directory, the journal's failure (if any)
/// and the fsync latency histogram (`le` bounds in seconds, counts per bucket, not cumulative).
Json durable_stats_to_json(const durable::DurableStats& s);


}  // namespace strata::protocol

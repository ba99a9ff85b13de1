#pragma once
// Engine results as JSON: rebuild reports (commit, plan, stats) and cumulative counters.

#include "engine/accel/report.h"
#include "engine/counters.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// The rebuild report document. A planned report has the same shape without any `ms` member
/// and without `phases`; its `memory_bytes` is whatever the report holds (the server fills in the
/// memory held now).
Json report_to_json(const RebuildReport& r);

/// The compacted BLASes' totals (a report's and GET /v1/stats' `memory_bytes.compaction`).
Json compaction_to_json(const CompactionTotals& c);

/// The cumulative counters document (GET /v1/stats `counters`).
Json counters_to_json(const EngineCounters& c);

}  // namespace strata::protocol

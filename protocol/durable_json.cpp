#include "protocol/durable_json.h"

#include "protocol/stat_names.h"

namespace strata::protocol {

Json durable_stats_to_json(const durable::DurableStats& s) {
    Json j = Json::object();
    j["directory"] = s.directory;
    j["fsync"] = durable::fsync_mode_name(s.mode);
    j["failed"] = s.failed;
    if (s.failed) j["failure"] = s.failure;
    if (!s.last_snapshot_error.empty()) j["last_snapshot_error"] = s.last_snapshot_error;
    add_stats(j, durable::DURABLE_COUNTERS, s);
    Json buckets = Json::array();
    for (std::size_t i = 0; i < s.fsync_buckets.size(); ++i) {
        buckets.push_back({{"le", i < durable::FSYNC_BOUNDS.size() ? Json(durable::FSYNC_BOUNDS[i])
                                                                   : Json("+Inf")},
                           {"count", s.fsync_buckets[i]}});
    }
    j["fsync_latency_seconds"] = std::move(buckets);
    return j;
}

}  // namespace strata::protocol

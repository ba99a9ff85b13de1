#include "protocol/durable_json.h"

namespace strata::protocol {

Json durable_stats_to_json(const durable::DurableStats& s) {
    Json j = Json::object();
    j["directory"] = s.directory;
    j["fsync"] = durable::fsync_mode_name(s.mode);
    j["failed"] = s.failed;
    if (s.failed) j["failure"] = s.failure;
    if (!s.last_snapshot_error.empty()) j["last_snapshot_error"] = s.last_snapshot_error;
    for (const durable::DurableCounterSpec& spec : durable::DURABLE_COUNTERS) {
        if (spec.count) {
            j[std::string(spec.name)] = s.*spec.count;
        } else {
            j[std::string(spec.name)] = s.*spec.real;
        }
    }
    Json buckets = Json::array();
    for (std::size_t i = 0; i < s.fsync_buckets.size(); ++i) {
        buckets.push_back({{"le", i < durable::FSYNC_BOUNDS.size() ? Json(durable::FSYNC_BOUNDS[i])
                                                                   : Json("+Inf")},
                           {"count", s.fsync_buckets[i]}});
    }
    j["fsync_latency_seconds"] = std::move(buckets);
    return j;
}

std::string durable_metric_name(const durable::DurableCounterSpec& spec) {
    std::string name = "strata_durable_" + std::string(spec.name);
    if (spec.unit == durable::DurableUnit::Milliseconds)
        name.replace(name.size() - 3, 3, "_seconds");
    return spec.cumulative ? name + "_total" : name;
}

double durable_metric_value(const durable::DurableCounterSpec& spec,
                            const durable::DurableStats& s) {
    const double v = spec.value(s);
    return spec.unit == durable::DurableUnit::Milliseconds ? v / 1000.0 : v;
}

}  // namespace strata::protocol

#include "protocol/report_json.h"

#include "protocol/stat_names.h"

namespace strata::protocol {

namespace {

Json entries_to_json(const std::vector<MeshBuildEntry>& entries, bool planned) {
    Json out = Json::array();
    for (const MeshBuildEntry& e : entries) {
        Json j = {{"mesh", e.mesh},
                  {"reason", build_reason_name(e.reason)},
                  {"primitives", e.primitives}};
        if (e.clusters != 0) {
            j["clusters"] = e.clusters;
            j["clusters_refit"] = e.clusters_refit;
            j["clusters_rebuilt"] = e.clusters_rebuilt;
        }
        if (!e.detail.empty()) j["detail"] = e.detail;
        if (!planned) j["ms"] = e.ms;
        // Only rebuilds measure their BLAS (a refit's size does not move).
        if (!planned && e.bytes != 0) j["bytes"] = e.bytes;
        if (!planned && e.uncompacted_bytes != 0) j["uncompacted_bytes"] = e.uncompacted_bytes;
        out.push_back(std::move(j));
    }
    return out;
}

}  // namespace

Json report_to_json(const RebuildReport& r) {
    Json tlas = {{"action", tlas_action_name(r.tlas_action)},
                 {"instances", r.tlas_instances},
                 {"strategy", r.tlas.strategy}};
    if (!r.planned) {
        tlas["ms"] = r.phases.tlas_ms;
        tlas["static_instances"] = r.tlas.static_instances;
        tlas["dynamic_instances"] = r.tlas.dynamic_instances;
        tlas["stale_copies"] = r.tlas.stale_copies;
        tlas["static_array"] = r.tlas.static_array;
        tlas["dynamic_array"] = r.tlas.dynamic_array;
        if (r.tlas.static_rebuild[0] != '\0') tlas["static_rebuild"] = r.tlas.static_rebuild;
        Json merge = {{"swapped", r.tlas.merge_swapped}, {"running", r.tlas.merge_running}};
        if (r.tlas.merge_swapped) merge["build_ms"] = r.tlas.merge_build_ms;
        if (r.tlas.merge_cancelled) merge["cancelled"] = true;
        tlas["merge"] = std::move(merge);
    }
    Json j = {{"version", r.version},
              {"planned", r.planned},
              {"tlas", std::move(tlas)},
              {"blas_rebuilds", r.blas_rebuilds},
              {"blas_refits", r.blas_refits},
              {"rebuilt", entries_to_json(r.rebuilt, r.planned)},
              {"refit", entries_to_json(r.refit, r.planned)},
              {"released", r.released},
              {"primitives_built", r.primitives_built},
              {"primitives_refit", r.primitives_refit},
              {"clusters_rebuilt", r.clusters_rebuilt},
              {"clusters_refit", r.clusters_refit},
              {"world_transforms", r.world_transforms},
              {"instances_changed", r.instances_changed},
              {"memory_bytes",
               {{"blas", r.memory_blas_bytes},
                {"tlas", r.memory_tlas_bytes},
                {"compaction", compaction_to_json(r.compaction)}}}};
    if (!r.planned) {
        j["ms"] = r.phases.total_ms;
        j["phases"] = {{"plan_ms", r.phases.plan_ms},
                       {"blas_ms", r.phases.blas_ms},
                       {"tlas_ms", r.phases.tlas_ms},
                       {"sync_ms", r.phases.sync_ms}};
    }
    return j;
}

Json compaction_to_json(const CompactionTotals& c) {
    return {{"meshes", c.meshes},
            {"uncompacted_bytes", c.uncompacted_bytes},
            {"bytes", c.bytes},
            {"saved_bytes", c.uncompacted_bytes - c.bytes}};
}

Json counters_to_json(const EngineCounters& c) {
    Json j = Json::object();
    add_stats(j, ENGINE_COUNTERS, c);
    return j;
}

}  // namespace strata::protocol

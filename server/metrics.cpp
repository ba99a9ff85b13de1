#include "server/metrics.h"

#include <cstdio>

namespace strata::server {

namespace {

void header(std::string& out, const char* name, const char* type, const char* help) {
    out += "# HELP ";
    out += name;
    out += ' ';
    out += help;
    out += "\n# TYPE ";
    out += name;
    out += ' ';
    out += type;
    out += '\n';
}

std::string number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

void metric(std::string& out, const char* name, const char* type, const char* help, double v) {
    header(out, name, type, help);
    out += name;
    out += ' ' + number(v) + '\n';
}

}  // namespace

void Histogram::observe(double seconds) {
    std::size_t i = 0;
    while (i < BOUNDS.size() && seconds > BOUNDS[i]) ++i;
    std::lock_guard lock(m_mutex);
    ++m_buckets[i];
    m_sum += seconds;
    ++m_count;
}

void Histogram::write(std::string& out, const char* name, const char* help) const {
    std::array<uint64_t, BOUNDS.size() + 1> buckets;
    double sum;
    uint64_t count;
    {
        std::lock_guard lock(m_mutex);
        buckets = m_buckets;
        sum = m_sum;
        count = m_count;
    }
    header(out, name, "histogram", help);
    uint64_t cumulative = 0;
    for (std::size_t i = 0; i < BOUNDS.size(); ++i) {
        cumulative += buckets[i];
        out += std::string(name) + "_bucket{le=\"" + number(BOUNDS[i]) + "\"} " +
               std::to_string(cumulative) + '\n';
    }
    out += std::string(name) + "_bucket{le=\"+Inf\"} " + std::to_string(count) + '\n';
    out += std::string(name) + "_sum " + number(sum) + '\n';
    out += std::string(name) + "_count " + std::to_string(count) + '\n';
}

void ServerMetrics::count_response(int status) {
    const int cls = status / 100;
    if (cls >= 1 && cls <= 5)
        m_responses[std::size_t(cls - 1)].fetch_add(1, std::memory_order_relaxed);
}

std::string ServerMetrics::prometheus_text(const Engine& engine) const {
    const EngineCounters c = engine.counters();
    std::string out;
    out.reserve(8192);
    for (const CounterSpec& spec : ENGINE_COUNTERS) {
        const std::string name = "strata_" + std::string(spec.name) + "_total";
        metric(out, name.c_str(), "counter", std::string(spec.help).c_str(), spec.value(c));
    }

    header(out, "strata_http_responses_total", "counter", "HTTP responses by status class.");
    for (std::size_t i = 0; i < m_responses.size(); ++i) {
        out += "strata_http_responses_total{code=\"" + std::to_string(i + 1) + "xx\"} " +
               std::to_string(m_responses[i].load(std::memory_order_relaxed)) + '\n';
    }

    const auto [version, counts] =
        engine.read([](const Scene& s) { return std::pair(s.version(), s.counts()); });
    metric(out, "strata_scene_version", "gauge", "Scene version (applied batches).",
           double(version));
    metric(out, "strata_scene_meshes", "gauge", "Meshes in the scene.", double(counts.meshes));
    metric(out, "strata_scene_instances", "gauge", "Instances in the scene.",
           double(counts.instances));
    metric(out, "strata_scene_triangles", "gauge", "Triangles over meshes, each counted once.",
           double(counts.triangles));
    header(out, "strata_accel_memory_bytes", "gauge",
           "Bytes Embree holds for acceleration structures.");
    out += "strata_accel_memory_bytes{level=\"blas\"} " +
           std::to_string(engine.memory_bytes(MemoryCategory::Blas)) + '\n';
    out += "strata_accel_memory_bytes{level=\"tlas\"} " +
           std::to_string(engine.memory_bytes(MemoryCategory::Tlas)) + '\n';

    // The incremental TLAS's tiers as the last commit left them.
    const TlasTiers tiers = engine.last_report().tlas;
    header(out, "strata_tlas_instances", "gauge",
           "Instances in each tier of the TLAS after the last commit (incremental strategy: "
           "static and dynamic; embree: all in static).");
    out += "strata_tlas_instances{tier=\"static\"} " + std::to_string(tiers.static_instances) +
           '\n';
    out += "strata_tlas_instances{tier=\"dynamic\"} " +
           std::to_string(tiers.dynamic_instances) + '\n';
    metric(out, "strata_tlas_stale_copies", "gauge",
           "Static-tier copies of instances edited since the static build (skipped by rays).",
           double(tiers.stale_copies));
    metric(out, "strata_tlas_merge_running", "gauge",
           "1 while a background TLAS merge was building after the last commit.",
           tiers.merge_running ? 1.0 : 0.0);

    commit_seconds.write(out, "strata_commit_duration_seconds",
                         "Wall time of commits (explicit and before renders).");
    render_seconds.write(out, "strata_render_duration_seconds",
                         "Wall time of renders, commit and encoding included.");
    return out;
}

void write_durable_metrics(std::string& out, const durable::DurableStats& stats) {
    using durable::DurableUnit;
    for (const durable::DurableCounterSpec& spec : durable::DURABLE_COUNTERS) {
        std::string name = "strata_durable_" + std::string(spec.name);
        double value = spec.value(stats);
        if (spec.unit == DurableUnit::Milliseconds) {
            // Prometheus wants base units.
            name.replace(name.size() - 3, 3, "_seconds");
            value /= 1000.0;
        }
        if (spec.cumulative) name += "_total";
        metric(out, name.c_str(), spec.cumulative ? "counter" : "gauge",
               std::string(spec.help).c_str(), value);
    }
    metric(out, "strata_durable_failed", "gauge",
           "1 when an fsync failed and the journal refuses batches.", stats.failed ? 1.0 : 0.0);
    const char* name = "strata_durable_fsync_duration_seconds";
    header(out, name, "histogram", "Wall time of journal fsyncs.");
    uint64_t cumulative = 0;
    for (std::size_t i = 0; i < stats.fsync_buckets.size(); ++i) {
        cumulative += stats.fsync_buckets[i];
        const std::string le =
            i < durable::FSYNC_BOUNDS.size() ? number(durable::FSYNC_BOUNDS[i]) : "+Inf";
        out += std::string(name) + "_bucket{le=\"" + le + "\"} " + std::to_string(cumulative) +
               '\n';
    }
    out += std::string(name) + "_sum " + number(stats.fsync_seconds) + '\n';
    out += std::string(name) + "_count " + std::to_string(cumulative) + '\n';
}

}  // namespace strata::server

#include "server/metrics.h"

#include <cstdio>
#include <iterator>
#include <string_view>
#include <utility>

#include "protocol/stat_names.h"

namespace strata::server {

namespace {

// Step: the tables of families that mirror a stats struct, one row per field.

using Replica = replica::ReplicaStatus;
constexpr MetricType COUNTER = MetricType::Counter;
constexpr MetricType GAUGE = MetricType::Gauge;
constexpr bool CUMULATIVE = true;
constexpr bool CURRENT = false;  ///< a gauge: the value now

constexpr StatSpec<FrontEndCounters> FRONT_END_METRICS[] = {
    {STRATA_STAT(FrontEndCounters, connections_open), "Open client connections.", StatUnit::Count,
     CURRENT},
    {STRATA_STAT(FrontEndCounters, requests_in_flight),
     "Requests a worker is handling (this /metrics request included).", StatUnit::Count, CURRENT},
    {STRATA_STAT(FrontEndCounters, connections_accepted), "Connections accepted.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(FrontEndCounters, connections_restricted),
     "Connections over a connection limit, served health checks only.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(FrontEndCounters, connections_refused),
     "Connections closed at once, over every limit.", StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(FrontEndCounters, timeouts),
     "Requests that did not arrive, and answers not taken, in time.", StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(FrontEndCounters, clients_gone),
     "Clients that disconnected while their request was being handled (their renders stop).",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(FrontEndCounters, reads_waiting),
     "Reads the front end holds until the scene reaches their min_version.", StatUnit::Count,
     CURRENT},
    {STRATA_STAT(FrontEndCounters, waits_refused),
     "Reads with a min_version answered 503 because too many were waiting already.",
     StatUnit::Count, CUMULATIVE},
};

constexpr StatSpec<StreamHubStats> STREAM_METRICS[] = {
    {STRATA_STAT(StreamHubStats, viewers), "Open frame streams (GET /v1/stream).", StatUnit::Count,
     CURRENT},
    {STRATA_STAT(StreamHubStats, event_clients), "Open event streams (GET /v1/events).",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(StreamHubStats, views), "Distinct views those streams render.", StatUnit::Count,
     CURRENT},
    {STRATA_STAT(StreamHubStats, frames_rendered),
     "Viewer renders (each shared by the viewers of its view).", StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(StreamHubStats, frames_sent), "Frames handed to viewers.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(StreamHubStats, render_errors), "Viewer renders that failed.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(StreamHubStats, commit_events), "Commit events published.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(StreamHubStats, commit_events_dropped),
     "Commit events dropped because 1024 were already waiting for the hub's thread.",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(StreamHubStats, renders_deferred),
     "Times a due viewer render waited for API renders or commits.", StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(StreamHubStats, frames_dropped),
     "Frames open viewers missed because a newer one replaced them (slow viewers).",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(StreamHubStats, highlight_encodes),
     "Frames encoded with a selected instance tinted (one per frame and instance).",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(StreamHubStats, held_bytes),
     "Frame bytes held for open viewers (pending and being written).", StatUnit::Bytes, CURRENT},
    {STRATA_STAT(StreamHubStats, view_bytes),
     "Memory the views of open frame streams hold (frame, instance ids, JPEGs).", StatUnit::Bytes,
     CURRENT},
    {STRATA_STAT(StreamHubStats, views_refused),
     "Frame streams refused because their new view was over --max-stream-mb.", StatUnit::Count,
     CUMULATIVE},
};

constexpr StatSpec<Replica> REPLICA_METRICS[] = {
    {STRATA_STAT(Replica, connected), "1 while the reader holds a connection to Redis.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, joined),
     "1 once the replica caught up with the log as it was at start (/readyz).", StatUnit::Count,
     CURRENT},
    {STRATA_STAT(Replica, stopped),
     "1 once the replica stopped following the log (a poisoned entry, a gap); see /readyz.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, applied_version), "Scene version this replica has applied.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, log_version), "Newest version this replica knows the log has.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, lag_entries), "Log entries this replica has not applied yet.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, lag_seconds),
     "How long the oldest unapplied log entry has waited (0 when caught up).", StatUnit::Seconds,
     CURRENT},
    {STRATA_STAT(Replica, entries_applied), "Log entries applied by this replica.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(Replica, appends), "Batches this replica appended to the log.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(Replica, append_conflicts),
     "Appends refused because the log had moved past the validated version.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(Replica, reconnects), "Reader reconnections to Redis.", StatUnit::Count,
     CUMULATIVE},
    {STRATA_STAT(Replica, snapshot_loaded_version),
     "Version of the newest Redis snapshot this replica loaded (0: none).", StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, snapshot_jumps),
     "Times this replica replaced its scene with a newer Redis snapshot because the log entries "
     "after its version had been trimmed.",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(Replica, snapshots_written), "Snapshots this replica stored in Redis.",
     StatUnit::Count, CUMULATIVE},
    {STRATA_STAT(Replica, snapshot_version), "Newest snapshot version known in Redis.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(Replica, entries_trimmed), "Log entries trimmed after this replica's snapshots.",
     StatUnit::Count, CUMULATIVE},
};

/// Converts to any field type: counts an aggregate's fields by how many it can be built from.
struct AnyField {
    template <class T>
    constexpr operator T() const noexcept;  // NOLINT: implicit by design; never defined
};

template <class T, std::size_t... I>
constexpr bool builds_from(std::index_sequence<I...>) {
    return requires {
        T{(void(I), AnyField{})...};
    };
}

/// The number of fields of the aggregate `T`.
template <class T, std::size_t N = 0>
constexpr std::size_t field_count() {
    if constexpr (builds_from<T>(std::make_index_sequence<N + 1>()))
        return field_count<T, N + 1>();
    else
        return N;
}

// A new field needs a row (or, not being a number, a place in the exceptions named here).
static_assert(field_count<FrontEndCounters>() == std::size(FRONT_END_METRICS));
static_assert(field_count<StreamHubStats>() == std::size(STREAM_METRICS));
static_assert(field_count<Replica>() == std::size(REPLICA_METRICS) + 2,  // log, stop_reason
              "every number of ReplicaStatus needs a row in REPLICA_METRICS");

// Step: building the registry.

std::string number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

MetricFamily scalar(std::string name, std::string help, MetricType type, MetricPart part,
                    std::function<double(const MetricsSnapshot&)> value) {
    if (type == MetricType::Counter) name += "_total";
    MetricFamily f{std::move(name), std::move(help), type, part, {}, {}};
    f.samples = [value = std::move(value)](const MetricsSnapshot& s) {
        return std::vector<MetricSample>{{"", value(s)}};
    };
    return f;
}

/// A family with one sample per value of `label`.
MetricFamily labelled(std::string name, std::string help, MetricType type, MetricPart part,
                      std::string label, std::vector<std::string> values,
                      std::function<double(const MetricsSnapshot&, std::size_t)> value) {
    MetricFamily f{std::move(name), std::move(help), type, part, {}, {}};
    f.samples = [label = std::move(label), values = std::move(values),
                 value = std::move(value)](const MetricsSnapshot& s) {
        std::vector<MetricSample> out;
        for (std::size_t i = 0; i < values.size(); ++i)
            out.push_back({label + "=\"" + values[i] + "\"", value(s, i)});
        return out;
    };
    return f;
}

MetricFamily histogram(std::string name, std::string help, MetricPart part,
                       std::function<HistogramCounts(const MetricsSnapshot&)> counts) {
    MetricFamily f{std::move(name), std::move(help), MetricType::Histogram, part, {}, {}};
    f.histogram = std::move(counts);
    return f;
}

/// A family per row of `table`, named by protocol::metric_name; `get` picks the struct from a
/// snapshot.
template <class S, std::size_t N, class Get>
void add_stats(std::vector<MetricFamily>& out, const StatSpec<S> (&table)[N], const char* prefix,
               MetricPart part, Get get) {
    for (const StatSpec<S>& row : table) {
        MetricFamily f{protocol::metric_name(prefix, row),
                       std::string(row.help),
                       row.cumulative ? COUNTER : GAUGE,
                       part,
                       {},
                       {}};
        f.samples = [&row, get](const MetricsSnapshot& s) {
            return std::vector<MetricSample>{{"", protocol::metric_value(row, get(s))}};
        };
        out.push_back(std::move(f));
    }
}

void add_engine_families(std::vector<MetricFamily>& out) {
    add_stats(out, ENGINE_COUNTERS, "strata_", MetricPart::Engine,
              [](const MetricsSnapshot& s) -> const EngineCounters& { return s.engine; });
    const auto gauge = [&](const char* name, const char* help,
                           std::function<double(const MetricsSnapshot&)> value) {
        out.push_back(scalar(name, help, GAUGE, MetricPart::Engine, std::move(value)));
    };
    gauge("strata_scene_version", "Scene version (applied batches).",
          [](const MetricsSnapshot& s) { return double(s.scene_version); });
    gauge("strata_scene_meshes", "Meshes in the scene.",
          [](const MetricsSnapshot& s) { return double(s.scene.meshes); });
    gauge("strata_scene_instances", "Instances in the scene.",
          [](const MetricsSnapshot& s) { return double(s.scene.instances); });
    gauge("strata_scene_triangles", "Triangles over meshes, each counted once.",
          [](const MetricsSnapshot& s) { return double(s.scene.triangles); });
    out.push_back(labelled(
        "strata_accel_memory_bytes", "Bytes Embree holds for acceleration structures.", GAUGE,
        MetricPart::Engine, "level", {"blas", "tlas"}, [](const MetricsSnapshot& s, std::size_t i) {
            return double(i == 0 ? s.blas_bytes : s.tlas_bytes);
        }));
    out.push_back(labelled(
        "strata_tlas_instances",
        "Instances in each tier of the TLAS after the last commit (incremental strategy: static "
        "and dynamic; embree: all in static).",
        GAUGE, MetricPart::Engine, "tier", {"static", "dynamic"},
        [](const MetricsSnapshot& s, std::size_t i) {
            return double(i == 0 ? s.tiers.static_instances : s.tiers.dynamic_instances);
        }));
    gauge("strata_tlas_stale_copies",
          "Static-tier copies of instances edited since the static build (skipped by rays).",
          [](const MetricsSnapshot& s) { return double(s.tiers.stale_copies); });
    gauge("strata_tlas_merge_running",
          "1 while a background TLAS merge was building after the last commit.",
          [](const MetricsSnapshot& s) { return s.tiers.merge_running ? 1.0 : 0.0; });
}

void add_server_families(std::vector<MetricFamily>& out) {
    out.push_back(
        labelled("strata_http_responses_total", "HTTP responses by status class.", COUNTER,
                 MetricPart::Server, "code", {"1xx", "2xx", "3xx", "4xx", "5xx"},
                 [](const MetricsSnapshot& s, std::size_t i) { return double(s.responses[i]); }));
    out.push_back(histogram(
        "strata_commit_duration_seconds", "Wall time of commits (explicit and before renders).",
        MetricPart::Server, [](const MetricsSnapshot& s) { return s.commit_seconds; }));
    out.push_back(histogram(
        "strata_render_duration_seconds", "Wall time of renders, commit and encoding included.",
        MetricPart::Server, [](const MetricsSnapshot& s) { return s.render_seconds; }));
    add_stats(out, FRONT_END_METRICS, "strata_http_", MetricPart::FrontEnd,
              [](const MetricsSnapshot& s) -> const FrontEndCounters& { return *s.front_end; });
}

void add_durable_families(std::vector<MetricFamily>& out) {
    add_stats(out, durable::DURABLE_COUNTERS, "strata_durable_", MetricPart::Durable,
              [](const MetricsSnapshot& s) -> const durable::DurableStats& { return *s.durable; });
    out.push_back(scalar("strata_durable_failed",
                         "1 when an fsync failed and the journal refuses batches.", GAUGE,
                         MetricPart::Durable,
                         [](const MetricsSnapshot& s) { return s.durable->failed ? 1.0 : 0.0; }));
    out.push_back(histogram("strata_durable_fsync_duration_seconds", "Wall time of journal fsyncs.",
                            MetricPart::Durable, [](const MetricsSnapshot& s) {
                                const durable::DurableStats& d = *s.durable;
                                return HistogramCounts{
                                    durable::FSYNC_BOUNDS,
                                    {d.fsync_buckets.begin(), d.fsync_buckets.end()},
                                    d.fsync_seconds};
                            }));
}

/// A gauge with one sample per named scene, labelled scene="NAME" (names need no escaping).
MetricFamily per_scene(std::string name, std::string help,
                       std::function<double(const NamedSceneMetrics&)> value) {
    MetricFamily f{std::move(name), std::move(help), MetricType::Gauge, MetricPart::Scenes, {}, {}};
    f.samples = [value = std::move(value)](const MetricsSnapshot& s) {
        std::vector<MetricSample> out;
        for (const NamedSceneMetrics& scene : *s.named_scenes)
            out.push_back({"scene=\"" + scene.name + "\"", value(scene)});
        return out;
    };
    return f;
}

constexpr StatSpec<SharedBlasStats> SHARED_BLAS_METRICS[] = {
    {STRATA_STAT(SharedBlasStats, count),
     "BLASes the scenes may share: whole BLASes built on the server's Embree device.",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(SharedBlasStats, holds),
     "Holds of a shared BLAS by a scene that did not build it (builds avoided now).",
     StatUnit::Count, CURRENT},
    {STRATA_STAT(SharedBlasStats, bytes), "Embree memory of the BLASes the scenes may share.",
     StatUnit::Bytes, CURRENT},
};

void add_scene_families(std::vector<MetricFamily>& out) {
    add_stats(out, SHARED_BLAS_METRICS, "strata_shared_blas_", MetricPart::Scenes,
              [](const MetricsSnapshot& s) -> const SharedBlasStats& { return s.shared_blases; });
    out.push_back(scalar("strata_named_scenes", "Named scenes held beside the default one.",
                         MetricType::Gauge, MetricPart::Scenes, [](const MetricsSnapshot& s) {
                             return double(s.named_scenes->size());
                         }));
    out.push_back(per_scene("strata_named_scene_version", "A named scene's version.",
                            [](const NamedSceneMetrics& m) { return double(m.version); }));
    out.push_back(per_scene("strata_named_scene_instances", "Instances in a named scene.",
                            [](const NamedSceneMetrics& m) { return double(m.instances); }));
    out.push_back(per_scene("strata_named_scene_triangles", "Triangles of a named scene's meshes.",
                            [](const NamedSceneMetrics& m) { return double(m.triangles); }));
    out.push_back(per_scene("strata_named_scene_blas_bytes", "Bytes a named scene's BLASes hold.",
                            [](const NamedSceneMetrics& m) { return double(m.blas_bytes); }));
}

std::vector<MetricFamily> build_registry() {
    std::vector<MetricFamily> out;
    add_engine_families(out);
    add_server_families(out);
    add_durable_families(out);
    add_stats(out, REPLICA_METRICS, "strata_replica_", MetricPart::Replica,
              [](const MetricsSnapshot& s) -> const Replica& { return *s.replica; });
    add_stats(out, STREAM_METRICS, "strata_stream_", MetricPart::Streams,
              [](const MetricsSnapshot& s) -> const StreamHubStats& { return *s.streams; });
    add_scene_families(out);
    return out;
}

// Step: the writer.

const char* type_name(MetricType t) {
    return t == MetricType::Counter ? "counter" : t == MetricType::Gauge ? "gauge" : "histogram";
}

void write_histogram(std::string& out, const std::string& name, const HistogramCounts& h) {
    uint64_t cumulative = 0;
    for (std::size_t i = 0; i < h.buckets.size(); ++i) {
        cumulative += h.buckets[i];
        const std::string le = i < h.bounds.size() ? number(h.bounds[i]) : "+Inf";
        out += name + "_bucket{le=\"" + le + "\"} " + std::to_string(cumulative) + '\n';
    }
    out += name + "_sum " + number(h.sum) + '\n';
    out += name + "_count " + std::to_string(cumulative) + '\n';
}

/// Whether `snapshot` has the part `family` belongs to.
bool exported(const MetricFamily& family, const MetricsSnapshot& snapshot) {
    switch (family.part) {
        case MetricPart::Engine:
        case MetricPart::Server:
            return true;
        case MetricPart::FrontEnd:
            return snapshot.front_end != nullptr;
        case MetricPart::Durable:
            return snapshot.durable.has_value();
        case MetricPart::Replica:
            return snapshot.replica.has_value();
        case MetricPart::Streams:
            return snapshot.streams.has_value();
        case MetricPart::Scenes:
            return snapshot.named_scenes.has_value();
    }
    return false;
}

}  // namespace

void Histogram::observe(double seconds) {
    std::size_t i = 0;
    while (i < BOUNDS.size() && seconds > BOUNDS[i]) ++i;
    std::lock_guard lock(m_mutex);
    ++m_buckets[i];
    m_sum += seconds;
}

HistogramCounts Histogram::counts() const {
    std::lock_guard lock(m_mutex);
    return {BOUNDS, {m_buckets.begin(), m_buckets.end()}, m_sum};
}

void ServerMetrics::count_response(int status) {
    const int cls = status / 100;
    if (cls >= 1 && cls <= 5)
        m_responses[std::size_t(cls - 1)].fetch_add(1, std::memory_order_relaxed);
}

std::array<uint64_t, 5> ServerMetrics::responses() const {
    std::array<uint64_t, 5> out{};
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = m_responses[i].load(std::memory_order_relaxed);
    return out;
}

const std::vector<MetricFamily>& metric_registry() {
    static const std::vector<MetricFamily> registry = build_registry();
    return registry;
}


std::string prometheus_text(const MetricsSnapshot& snapshot) {
    std::string out;
    out.reserve(16384);
    for (const MetricFamily& f : metric_registry()) {
        if (!exported(f, snapshot)) continue;
        out += "# HELP " + f.name + ' ' + f.help + "\n# TYPE " + f.name + ' ' + type_name(f.type) +
               '\n';
        if (f.type == MetricType::Histogram) {
            write_histogram(out, f.name, f.histogram(snapshot));
            continue;
        }
        for (const MetricSample& sample : f.samples(snapshot)) {
            out += f.name;
            if (!sample.labels.empty()) out += '{' + sample.labels + '}';
            out += ' ' + number(sample.value) + '\n';
        }
    }
    return out;
}

std::string metrics_markdown_table() {
    static const char* const PARTS[] = {"engine",   "server",  "front end (connections)",
                                        "`--data`", "`--log`", "streams (viewer, events)",
                                        "named scenes"};
    std::string out = "| series | type | exported by | what it is |\n|---|---|---|---|\n";
    for (const MetricFamily& f : metric_registry()) {
        out += "| `" + f.name + "` | " + type_name(f.type) + " | " + PARTS[int(f.part)] + " | " +
               f.help + " |\n";
    }
    return out;
}

}  // namespace strata::server

#pragma once
// Every series GET /metrics exports, declared once in one registry (metric_registry()), and the
// one writer of the Prometheus text exposition (format 0.0.4). A family reads its value from a
// MetricsSnapshot that a scrape takes once; the parts of the server that do not exist (no data
// directory, no edit log, no streams) leave their families out.
//
// Families that mirror a stats struct (engine counters, the data directory, the front end, the
// streams, the replica) are named after the struct's field: the name is the field's name with the
// part's prefix, `_total` for counters and `_seconds` for times, so a field is found by its
// exported name. Each such table is checked against its struct's field count (metrics.cpp), and
// protocol/README.md lists the registry (tests/server/metrics_registry_test.cpp).

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/accel/blas_pool.h"
#include "engine/durable/durable_stats.h"
#include "engine/engine.h"
#include "server/front_end_counters.h"
#include "server/replica/replica.h"
#include "server/stream_hub.h"

namespace strata::server {

/// The bucket counts of a histogram at one moment.
struct HistogramCounts {
    std::span<const double> bounds;  ///< upper bounds, seconds
    std::vector<uint64_t> buckets;   ///< one per bound, then the count above every bound
    double sum = 0.0;
};

/// A Prometheus histogram with fixed buckets (seconds), cheap enough to observe on every request.
class Histogram {
public:
    static constexpr std::array<double, 14> BOUNDS = {
        0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0};

    void observe(double seconds);
    HistogramCounts counts() const;

private:
    mutable std::mutex m_mutex;
    std::array<uint64_t, BOUNDS.size() + 1> m_buckets{};  ///< last: above every bound
    double m_sum = 0.0;
};

/// What the server measures itself.
class ServerMetrics {
public:
    /// Counts one response by status class (1xx .. 5xx).
    void count_response(int status);
    /// Responses so far by status class: [0] is 1xx.
    std::array<uint64_t, 5> responses() const;

    Histogram commit_seconds;
    Histogram render_seconds;

private:
    std::array<std::atomic<uint64_t>, 5> m_responses{};
};

/// One named scene's numbers (named_scenes.h), for its labelled series.
struct NamedSceneMetrics {
    std::string name;
    uint64_t version = 0;
    uint64_t instances = 0;
    uint64_t triangles = 0;
    uint64_t blas_bytes = 0;
};

/// Everything one scrape reads, taken once.
struct MetricsSnapshot {
    EngineCounters engine;
    uint64_t scene_version = 0;
    SceneCounts scene;
    uint64_t blas_bytes = 0;
    uint64_t tlas_bytes = 0;
    TlasTiers tiers;  ///< as the last commit left them
    std::array<uint64_t, 5> responses{};
    HistogramCounts commit_seconds;
    HistogramCounts render_seconds;
    const FrontEndCounters* front_end = nullptr;
    std::optional<durable::DurableStats> durable;
    std::optional<replica::ReplicaStatus> replica;
    std::optional<StreamHubStats> streams;
    /// The named scenes beside the default one (the server always has the directory).
    std::optional<std::vector<NamedSceneMetrics>> named_scenes;
    /// The BLASes the scenes share (engine/accel/blas_pool.h), with the directory.
    SharedBlasStats shared_blases;
};

/// The parts of the server a family belongs to (the README groups the table by it).
enum class MetricPart : uint8_t { Engine, Server, FrontEnd, Durable, Replica, Streams, Scenes };

enum class MetricType : uint8_t { Counter, Gauge, Histogram };

/// One sample of a family: its labels (`code="2xx"`, or empty) and value.
struct MetricSample {
    std::string labels;
    double value = 0.0;
};

/// One family of series.
struct MetricFamily {
    std::string name;
    std::string help;
    MetricType type = MetricType::Gauge;
    MetricPart part = MetricPart::Engine;
    /// Counters and gauges: the samples of a snapshot.
    std::function<std::vector<MetricSample>(const MetricsSnapshot&)> samples;
    /// Histograms: the bucket counts of a snapshot.
    std::function<HistogramCounts(const MetricsSnapshot&)> histogram;
};

/// Every family /metrics can export, in the order it writes them.
const std::vector<MetricFamily>& metric_registry();

/// The whole /metrics document.
std::string prometheus_text(const MetricsSnapshot& snapshot);

/// The registry as a Markdown table (protocol/README.md, between generated-region markers).
std::string metrics_markdown_table();

}  // namespace strata::server

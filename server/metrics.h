#pragma once
// Server-side metrics and the Prometheus text exposition (format 0.0.4). Engine counters are read
// from Engine::counters() at scrape time; the server adds request counts by status class and
// fixed-bucket histograms of commit and render durations.

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "engine/durable/durable_stats.h"
#include "engine/engine.h"

namespace strata::server {

/// A Prometheus histogram with fixed buckets (seconds), cheap enough to observe on every request.
class Histogram {
public:
    static constexpr std::array<double, 14> BOUNDS = {
        0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0};

    void observe(double seconds);
    /// Appends `# HELP`, `# TYPE` and the bucket, sum and count lines.
    void write(std::string& out, const char* name, const char* help) const;

private:
    mutable std::mutex m_mutex;
    std::array<uint64_t, BOUNDS.size() + 1> m_buckets{};  ///< last: above every bound (+Inf only)
    double m_sum = 0.0;
    uint64_t m_count = 0;
};

/// Everything the server measures itself.
class ServerMetrics {
public:
    /// Counts one response by status class (1xx .. 5xx).
    void count_response(int status);
    Histogram commit_seconds;
    Histogram render_seconds;

    /// The whole /metrics document.
    std::string prometheus_text(const Engine& engine) const;

private:
    std::array<std::atomic<uint64_t>, 5> m_responses{};
};

/// Appends the data directory's numbers (strata_durable_*) and the fsync latency histogram.
void write_durable_metrics(std::string& out, const durable::DurableStats& stats);

}  // namespace strata::server

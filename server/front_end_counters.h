#pragma once
// What the front end (reactor.h) has seen of connections, for /metrics (metrics.h exports each
// field under its own name). Written by the reactor thread, read by whichever worker answers
// /metrics.

#include <atomic>
#include <cstdint>

namespace strata::server {

struct FrontEndCounters {
    std::atomic<uint64_t> connections_open{0};
    std::atomic<uint64_t> requests_in_flight{0};  ///< handed to a worker, not yet answered
    std::atomic<uint64_t> connections_accepted{0};
    /// Over a connection limit: served health checks only.
    std::atomic<uint64_t> connections_restricted{0};
    std::atomic<uint64_t> connections_refused{0};  ///< closed at once: over every limit
    std::atomic<uint64_t> timeouts{0};             ///< 408s and abandoned writes
    std::atomic<uint64_t> clients_gone{0};  ///< clients that left while a worker had their request
    std::atomic<uint64_t> reads_waiting{0};  ///< held until the scene reaches their min_version
    std::atomic<uint64_t> waits_refused{0};  ///< 503s: too many reads waiting already
};

}  // namespace strata::server

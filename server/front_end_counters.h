#pragma once
// What the front end (reactor.h) has seen of connections, for /metrics. Written by the reactor
// thread, read by whichever worker answers /metrics.

#include <atomic>
#include <cstdint>
#include <string>

namespace strata::server {

struct FrontEndCounters {
    std::atomic<uint64_t> accepted{0};
    std::atomic<uint64_t> refused{0};      ///< closed at once: over every limit, reserve included
    std::atomic<uint64_t> restricted{0};   ///< over a limit: served health checks only
    std::atomic<uint64_t> timeouts{0};     ///< 408s and abandoned writes
    std::atomic<uint64_t> client_gone{0};  ///< clients that left while a worker had their request
    std::atomic<uint64_t> open{0};
    std::atomic<uint64_t> handling{0};  ///< requests handed to a worker, not yet answered

    /// Appends the Prometheus text of these counters.
    void write_prometheus(std::string& out) const;
};

}  // namespace strata::server

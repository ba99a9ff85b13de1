#pragma once
// Reads held by the front end until their scene reaches the min_version they ask for (reactor.h,
// the Waiting phase): who waits, for which version, until when; at most --max-waiting-reads in
// all and --max-waiting-reads-per-client each. A held read costs its buffered bytes, no thread.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "server/client_quota.h"
#include "server/request_reader.h"

namespace strata::server {

class WaitingReads {
public:
    using Clock = std::chrono::steady_clock;

    /// One held read.
    struct Waiter {
        uint64_t conn = 0;
        std::string client;
        std::string scene;    ///< the named scene it reads; "" for the default scene
        uint64_t wanted = 0;  ///< its min_version
        Clock::time_point deadline{};
        PreparedRequest request;
    };

    WaitingReads(std::size_t max_total, std::size_t max_per_client)
        : m_quota(max_total, max_per_client) {}

    /// True while `client` may hold one more read.
    bool admits(const std::string& client) const { return m_quota.admits(client); }
    /// Why `client` may not: the counts and the flags that bound them.
    std::string refusal(const std::string& client) const;
    void park(Waiter&& waiter);
    /// Forgets the read of connection `conn` (its client left), if it holds one.
    void forget(uint64_t conn);
    /// A scene's version now, by name ("" for the default scene).
    using VersionOf = std::function<uint64_t(std::string_view scene)>;
    /// The reads whose scene's version arrived or whose wait is over (all of them when `all`),
    /// oldest first; they are no longer held.
    std::vector<Waiter> take_due(const VersionOf& version, Clock::time_point now, bool all);
    bool empty() const { return m_waiters.empty(); }
    std::size_t size() const { return m_waiters.size(); }

private:
    ClientQuota m_quota;
    std::vector<Waiter> m_waiters;  ///< oldest first
};

}  // namespace strata::server

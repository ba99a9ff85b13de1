#include "server/waiting_reads.h"

#include <algorithm>

namespace strata::server {

std::string WaitingReads::refusal(const std::string& client) const {
    return "too many reads are waiting for a min_version already (" +
           std::to_string(m_quota.held(client)) + " from this client, " +
           std::to_string(m_quota.total()) + " in all; --max-waiting-reads-per-client " +
           std::to_string(m_quota.per_client_limit()) + ", --max-waiting-reads " +
           std::to_string(m_quota.total_limit()) + ")";
}

void WaitingReads::park(Waiter&& waiter) {
    m_quota.take(waiter.client);
    m_waiters.push_back(std::move(waiter));
}

void WaitingReads::forget(uint64_t conn) {
    const auto it = std::find_if(m_waiters.begin(), m_waiters.end(),
                                 [conn](const Waiter& w) { return w.conn == conn; });
    if (it == m_waiters.end()) return;
    m_quota.give_back(it->client);
    m_waiters.erase(it);
}

std::vector<WaitingReads::Waiter> WaitingReads::take_due(const VersionOf& version,
                                                         Clock::time_point now, bool all) {
    std::vector<Waiter> due;
    std::vector<Waiter> still;
    for (Waiter& w : m_waiters) {
        if (!all && now < w.deadline && version(w.scene) < w.wanted) {
            still.push_back(std::move(w));
            continue;
        }
        m_quota.give_back(w.client);
        due.push_back(std::move(w));
    }
    m_waiters.swap(still);
    return due;
}

}  // namespace strata::server

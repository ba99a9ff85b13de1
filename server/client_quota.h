#pragma once
// What each client address holds (connections, waiting reads), and the total, against a limit
// for each: the front end's admission rule, in one place.

#include <cstddef>
#include <string>
#include <unordered_map>

namespace strata::server {

class ClientQuota {
public:
    ClientQuota(std::size_t total_limit, std::size_t per_client_limit)
        : m_total_limit(total_limit), m_per_client_limit(per_client_limit) {}

    /// True while both `client` and everyone together are under their limits.
    bool admits(const std::string& client) const {
        return m_total < m_total_limit && held(client) < m_per_client_limit;
    }
    void take(const std::string& client) {
        ++m_held[client];
        ++m_total;
    }
    void give_back(const std::string& client) {
        if (auto it = m_held.find(client); it != m_held.end() && --it->second == 0)
            m_held.erase(it);
        --m_total;
    }
    std::size_t held(const std::string& client) const {
        const auto it = m_held.find(client);
        return it == m_held.end() ? 0 : it->second;
    }
    std::size_t total() const { return m_total; }
    std::size_t total_limit() const { return m_total_limit; }
    std::size_t per_client_limit() const { return m_per_client_limit; }

private:
    std::size_t m_total_limit;
    std::size_t m_per_client_limit;
    std::unordered_map<std::string, std::size_t> m_held;
    std::size_t m_total = 0;
};

}  // namespace strata::server

#pragma once
// The listening socket, opened by Strata rather than httplib: a clear error for every way binding
// can fail (an unresolvable --host, a port another process holds, an address no interface has),
// a configurable backlog, and SO_REUSEADDR only. httplib sets SO_REUSEPORT, with which a second
// server starts on a port that is in use and the kernel splits connections between two scenes.

#include <string>
#include <vector>

#include "engine/core/result.h"

namespace strata::server {

/// The numeric addresses `host` stands for (an address or a name; IPv6 may be bracketed), or an
/// error saying that it resolves to none.
Result<std::vector<std::string>> resolve_host(const std::string& host);

class Listener {
public:
    Listener() = default;
    ~Listener() { close(); }
    Listener(Listener&& other) noexcept;
    Listener& operator=(Listener&& other) noexcept;
    Listener(const Listener&) = delete;
    Listener& operator=(const Listener&) = delete;

    /// Resolves `host` (an address or a name; IPv6 may be bracketed), binds `port` (0: any free
    /// one) and listens with `backlog`.
    static Result<Listener> open(const std::string& host, int port, int backlog);

    int fd() const { return m_fd; }
    /// The port bound (the one the kernel chose when asked for 0).
    int port() const { return m_port; }
    void close();

private:
    int m_fd = -1;
    int m_port = 0;
};

}  // namespace strata::server

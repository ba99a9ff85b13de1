#include "server/listener.h"

#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace strata::server {

namespace {

std::string why_bind_failed(int err) {
    switch (err) {
        case EADDRINUSE:
            return "the port is in use (is another server running?)";
        case EADDRNOTAVAIL:
            return "no network interface of this machine has that address";
        case EACCES:
            return "permission denied (ports below 1024 need privileges)";
        default:
            return std::strerror(err);
    }
}

int bound_port(int fd) {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return -1;
    if (addr.ss_family == AF_INET) return ntohs(reinterpret_cast<sockaddr_in&>(addr).sin_port);
    return ntohs(reinterpret_cast<sockaddr_in6&>(addr).sin6_port);
}

/// getaddrinfo for a passive TCP socket; the error names the host.
Result<addrinfo*> lookup(const std::string& host_in, int port) {
    std::string host = host_in;
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
        host = host.substr(1, host.size() - 2);
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    addrinfo* found = nullptr;
    const std::string service = std::to_string(port);
    if (const int rc = getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0)
        return failure(ErrorCode::InvalidArgument,
                          "--host '" + host_in +
                              "' is not an IP address or a name this machine resolves (" +
                              gai_strerror(rc) + ")");
    return found;
}

}  // namespace

Listener::Listener(Listener&& other) noexcept
    : m_fd(std::exchange(other.m_fd, -1)), m_port(other.m_port) {}

Listener& Listener::operator=(Listener&& other) noexcept {
    if (this != &other) {
        close();
        m_fd = std::exchange(other.m_fd, -1);
        m_port = other.m_port;
    }
    return *this;
}

void Listener::close() {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = -1;
}

Result<std::vector<std::string>> resolve_host(const std::string& host) {
    auto found = lookup(host, 0);
    if (!found) return Unexpected(found.error());
    std::vector<std::string> out;
    for (addrinfo* a = found.value(); a != nullptr; a = a->ai_next) {
        char buf[NI_MAXHOST] = {};
        if (getnameinfo(a->ai_addr, a->ai_addrlen, buf, sizeof buf, nullptr, 0, NI_NUMERICHOST) ==
            0)
            out.emplace_back(buf);
    }
    freeaddrinfo(found.value());
    return out;
}

Result<Listener> Listener::open(const std::string& host_in, int port, int backlog) {
    const std::string where = "--host '" + host_in + "' port " + std::to_string(port);
    auto lookup_result = lookup(host_in, port);
    if (!lookup_result)
        return failure(ErrorCode::InvalidArgument,
                          "cannot listen: " + lookup_result.error().message);
    addrinfo* found = lookup_result.value();
    int last_error = 0;
    Listener l;
    for (addrinfo* a = found; a != nullptr && l.m_fd < 0; a = a->ai_next) {
        const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) {
            last_error = errno;
            continue;
        }
        // SO_REUSEADDR lets a restarted server bind while old connections sit in TIME_WAIT; on
        // Linux it never lets two sockets listen on one port (SO_REUSEPORT would).
        const int one = 1;
        setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, backlog) != 0) {
            last_error = errno;
            ::close(fd);
            continue;
        }
        l.m_fd = fd;
        l.m_port = bound_port(fd);
    }
    freeaddrinfo(found);
    if (l.m_fd < 0)
        return failure(ErrorCode::InvalidArgument,
                          "cannot listen on " + where + ": " + why_bind_failed(last_error));
    return l;
}

}  // namespace strata::server

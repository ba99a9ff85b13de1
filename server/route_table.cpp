#include "server/route_table.h"

#include <algorithm>
#include <cstring>

#include <spdlog/spdlog.h>

#include "protocol/safe_text.h"
#include "server/direct_response.h"

namespace strata::server {

namespace {

thread_local RequestContext* t_current = nullptr;

/// Reads the request from memory and collects the response in memory.
class MemoryStream : public httplib::Stream {
public:
    MemoryStream(std::string_view in, const Peer& peer, std::string& out)
        : m_in(in), m_peer(peer), m_out(out) {}

    bool is_readable() const override { return m_pos < m_in.size(); }
    bool is_writable() const override { return true; }
    ssize_t read(char* ptr, size_t size) override {
        const std::size_t n = std::min(size, m_in.size() - m_pos);
        std::memcpy(ptr, m_in.data() + m_pos, n);
        m_pos += n;
        return ssize_t(n);
    }
    ssize_t write(const char* ptr, size_t size) override {
        m_out.append(ptr, size);
        return ssize_t(size);
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        ip = m_peer.ip;
        port = m_peer.port;
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        ip = m_peer.local_ip;
        port = m_peer.local_port;
    }
    // httplib only compares this with FD_SETSIZE (for its select() calls, which a memory stream
    // never reaches); 0 is what its own BufferStream answers.
    socket_t socket() const override { return 0; }

private:
    std::string_view m_in;
    std::size_t m_pos = 0;
    const Peer& m_peer;
    std::string& m_out;
};

/// Sets the thread's current request for the duration of a scope.
class ContextScope {
public:
    explicit ContextScope(RequestContext& c) { t_current = &c; }
    ~ContextScope() { t_current = nullptr; }
    ContextScope(const ContextScope&) = delete;
    ContextScope& operator=(const ContextScope&) = delete;
};

}  // namespace

RequestContext* current_request() {
    return t_current;
}

std::string RouteTable::handle(std::string_view wire_bytes, const Peer& peer, bool close,
                               RequestContext& context) {
    ContextScope scope(context);
    std::string out;
    try {
        MemoryStream stream(wire_bytes, peer, out);
        bool closed = false;
        if (process_request(stream, close, closed, nullptr) && !out.empty()) return out;
        spdlog::error("the router produced no response for a checked request");
    } catch (const std::exception& e) {
        spdlog::error("exception outside the route handlers: {}",
                      protocol::escape_for_log(e.what()));
    } catch (...) {
        spdlog::error("unknown exception outside the route handlers");
    }
    context.close = true;
    return problem_bytes(protocol::make_problem(protocol::ProblemType::Internal,
                                                "internal error while handling the request"),
                         true);
}

}  // namespace strata::server

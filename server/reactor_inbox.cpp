#include "server/reactor_inbox.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include <spdlog/spdlog.h>

namespace strata::server {

// Made at construction, not when the loop opens: drain() may wake it from another thread at any
// time.
ReactorInbox::ReactorInbox() {
    m_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (m_fd < 0) m_error = errno;
}

ReactorInbox::~ReactorInbox() {
    if (m_fd >= 0) ::close(m_fd);
}

Result<int> ReactorInbox::fd() const {
    if (m_fd >= 0) return m_fd;
    return failure(ErrorCode::Internal, std::string("eventfd: ") + std::strerror(m_error));
}

void ReactorInbox::post(Completion&& done) {
    {
        std::lock_guard lock(m_mutex);
        m_done.push_back(std::move(done));
    }
    wake();
}

void ReactorInbox::post_stream(uint64_t conn) {
    {
        std::lock_guard lock(m_mutex);
        m_streams.push_back(conn);
    }
    wake();
}

void ReactorInbox::wake() {
    const uint64_t one = 1;
    // EAGAIN: the counter is saturated, so the front end is woken anyway.
    if (m_fd >= 0 && ::write(m_fd, &one, sizeof one) < 0 && errno != EAGAIN)
        spdlog::error("waking the front end: write(eventfd): {}", std::strerror(errno));
}

void ReactorInbox::clear_wake() {
    uint64_t count = 0;
    if (::read(m_fd, &count, sizeof count) < 0 && errno != EAGAIN)
        spdlog::error("reading the eventfd: {}", std::strerror(errno));
}

std::vector<ReactorInbox::Completion> ReactorInbox::take_completions() {
    std::vector<Completion> done;
    std::lock_guard lock(m_mutex);
    done.swap(m_done);
    return done;
}

std::vector<uint64_t> ReactorInbox::take_streams() {
    std::vector<uint64_t> ready;
    std::lock_guard lock(m_mutex);
    ready.swap(m_streams);
    return ready;
}

}  // namespace strata::server

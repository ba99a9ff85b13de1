#include "server/stream_channel.h"

namespace strata::server {

StreamChannel::StreamChannel(Mode mode, std::chrono::milliseconds min_interval,
                             std::size_t max_queued_bytes)
    : m_mode(mode), m_min_interval(min_interval), m_max_queued_bytes(max_queued_bytes) {}

bool StreamChannel::offer(Part part) {
    std::function<void()> wake;
    {
        std::lock_guard lock(m_mutex);
        if (m_gone || m_ended) return false;
        if (m_mode == Mode::Latest) {
            m_dropped += m_pending.size();
            m_pending.clear();
            m_pending_bytes = 0;
        }
        m_pending_bytes += part->size();
        m_pending.push_back(std::move(part));
        // Queue: the oldest go first; the newest part is always kept, even alone over the cap.
        while (m_pending.size() > 1 && m_pending_bytes > m_max_queued_bytes) {
            m_pending_bytes -= m_pending.front()->size();
            m_pending.pop_front();
            ++m_dropped;
        }
        wake = m_wake;
    }
    // Outside the lock: the reactor's wake takes its own lock.
    if (wake) wake();
    return true;
}

void StreamChannel::end() {
    std::function<void()> wake;
    {
        std::lock_guard lock(m_mutex);
        if (m_ended) return;
        m_ended = true;
        m_dropped += m_pending.size();
        m_pending.clear();
        m_pending_bytes = 0;
        wake = m_wake;
    }
    if (wake) wake();
}

bool StreamChannel::gone() const {
    std::lock_guard lock(m_mutex);
    return m_gone;
}

void StreamChannel::attach(std::function<void()> wake) {
    std::lock_guard lock(m_mutex);
    m_wake = std::move(wake);
}

void StreamChannel::detach() {
    std::lock_guard lock(m_mutex);
    m_gone = true;
    m_wake = nullptr;
    m_pending.clear();
    m_pending_bytes = 0;
    m_writing.reset();
}

StreamChannel::Part StreamChannel::take() {
    std::lock_guard lock(m_mutex);
    if (m_pending.empty()) return nullptr;
    m_writing = std::move(m_pending.front());
    m_pending.pop_front();
    m_pending_bytes -= m_writing->size();
    return m_writing;
}

void StreamChannel::written() {
    std::lock_guard lock(m_mutex);
    if (m_writing) ++m_sent;
    m_writing.reset();
}

bool StreamChannel::ended() const {
    std::lock_guard lock(m_mutex);
    return m_ended;
}

std::size_t StreamChannel::held_bytes() const {
    std::lock_guard lock(m_mutex);
    return m_pending_bytes + (m_writing ? m_writing->size() : 0);
}

uint64_t StreamChannel::dropped() const {
    std::lock_guard lock(m_mutex);
    return m_dropped;
}

uint64_t StreamChannel::sent() const {
    std::lock_guard lock(m_mutex);
    return m_sent;
}

}  // namespace strata::server

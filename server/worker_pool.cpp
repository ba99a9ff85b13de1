#include "server/worker_pool.h"

#include <algorithm>

namespace strata::server {

WorkerPool::WorkerPool(std::size_t threads) {
    threads = std::max<std::size_t>(1, threads);
    const std::size_t reserve = threads >= 4 ? 2 : threads - 1;
    m_heavy_limit = threads - reserve;
    m_threads.reserve(threads);
    for (std::size_t i = 0; i < threads; ++i) m_threads.emplace_back([this] { run(); });
}

WorkerPool::~WorkerPool() {
    shutdown();
}

void WorkerPool::submit(bool heavy, std::function<void()> job) {
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping) return;
        (heavy ? m_heavy : m_light).push_back(std::move(job));
    }
    m_ready.notify_one();
}

void WorkerPool::shutdown() {
    {
        std::lock_guard lock(m_mutex);
        if (m_stopping && m_threads.empty()) return;
        m_stopping = true;
        m_light.clear();
        m_heavy.clear();
    }
    m_ready.notify_all();
    for (std::thread& t : m_threads) {
        if (t.joinable()) t.join();
    }
    m_threads.clear();
}

void WorkerPool::run() {
    std::unique_lock lock(m_mutex);
    for (;;) {
        // Light jobs first; a heavy one only while the reserve stays free for light ones.
        m_ready.wait(lock, [&] {
            return m_stopping || !m_light.empty() ||
                   (!m_heavy.empty() && m_heavy_running < m_heavy_limit);
        });
        if (m_stopping) return;
        const bool heavy = m_light.empty();
        std::deque<std::function<void()>>& queue = heavy ? m_heavy : m_light;
        std::function<void()> job = std::move(queue.front());
        queue.pop_front();
        m_heavy_running += heavy;
        lock.unlock();
        job();
        job = nullptr;  // destroy what it captured outside the lock
        lock.lock();
        m_heavy_running -= heavy;
        // A heavy slot came free: a worker waiting only on the limit may now start one.
        if (heavy) m_ready.notify_one();
    }
}

}  // namespace strata::server

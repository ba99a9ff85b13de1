#pragma once
// The threads that run route handlers. They never touch a socket: the front end hands them a
// complete request and writes their answer, so a slow or idle client never holds one.
//
// Renders and commits ("heavy" jobs) may take seconds and are serialised by the engine anyway:
// they may occupy all workers but a reserve, so that edits, scene reads and metrics keep flowing
// while frames render.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace strata::server {

class WorkerPool {
public:
    /// Starts `threads` workers (at least one).
    explicit WorkerPool(std::size_t threads);
    /// Drops the jobs that have not started and joins the workers.
    ~WorkerPool();
    WorkerPool(const WorkerPool&) = delete;
    WorkerPool& operator=(const WorkerPool&) = delete;

    /// Queues a job; jobs of one kind start in the order they were submitted.
    void submit(bool heavy, std::function<void()> job);

    /// Drops the queued jobs, waits for the running ones and stops the workers. Idempotent.
    void shutdown();

    /// Workers heavy jobs may occupy at once: all but a reserve of up to two.
    std::size_t heavy_limit() const { return m_heavy_limit; }

private:
    void run();

    std::mutex m_mutex;
    std::condition_variable m_ready;
    std::deque<std::function<void()>> m_light;
    std::deque<std::function<void()>> m_heavy;
    std::size_t m_heavy_running = 0;
    std::size_t m_heavy_limit = 1;
    bool m_stopping = false;
    std::vector<std::thread> m_threads;
};

}  // namespace strata::server

#pragma once
// One long-lived streaming response between a producer (the stream hub, stream_hub.h) and the
// front end (reactor.h), which writes its parts as they come: the live viewer's JPEG frames
// (multipart/x-mixed-replace) and its commit events (text/event-stream).
//
// Memory is bounded per client whatever its speed. A Latest channel holds one pending part: a
// newer frame replaces one the client has not started to read (a slow viewer sees fewer frames,
// always the newest). A Queue channel keeps every part up to a byte cap, then drops the oldest
// (events are small; a client that far behind gets told how many it missed).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

namespace strata::server {

class StreamChannel {
public:
    enum class Mode : uint8_t { Latest, Queue };
    using Part = std::shared_ptr<const std::string>;

    /// `min_interval`: the front end writes parts no more often than this. The response's head
    /// is written by the front end before the first part.
    explicit StreamChannel(Mode mode, std::chrono::milliseconds min_interval = {},
                           std::size_t max_queued_bytes = 256 * 1024);

    // Producer side (any thread).

    /// Queues a part (Latest: replaces the pending one). False once the client has left or the
    /// stream ended: the producer drops the channel.
    bool offer(Part part);
    /// Ends the stream: the part being written finishes, pending ones are dropped, the
    /// connection closes.
    void end();
    /// True once the client left (or the front end dropped the connection).
    bool gone() const;

    // Front-end side (the reactor thread).

    /// Called when the head is about to be written: `wake` is called (from the producer's
    /// thread) whenever a part is offered.
    void attach(std::function<void()> wake);
    /// The connection is closed: offers fail from now on, and `wake` is never called again.
    void detach();
    /// The next part to write, or null when none is pending.
    Part take();
    /// The part taken last has been written in full.
    void written();
    /// True once end() was called (pending parts are gone).
    bool ended() const;

    std::chrono::milliseconds min_interval() const { return m_min_interval; }

    /// Bytes held for this client: pending parts and the one being written.
    std::size_t held_bytes() const;
    /// Parts dropped unsent (Latest: replaced; Queue: over the cap).
    uint64_t dropped() const;
    /// Parts written in full.
    uint64_t sent() const;

private:
    const Mode m_mode;
    const std::chrono::milliseconds m_min_interval;
    const std::size_t m_max_queued_bytes;

    mutable std::mutex m_mutex;
    std::deque<Part> m_pending;
    std::size_t m_pending_bytes = 0;
    Part m_writing;
    std::function<void()> m_wake;
    bool m_gone = false;
    bool m_ended = false;
    uint64_t m_dropped = 0;
    uint64_t m_sent = 0;
};

}  // namespace strata::server

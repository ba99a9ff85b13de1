#pragma once
// What other threads hand the front end's thread (reactor.h): workers' answers, streams that
// have a part to send, and wake-ups (a drain), through one eventfd the epoll loop watches.

#include <cstdint>
#include <mutex>
#include <vector>

#include "engine/core/result.h"
#include "server/application.h"

namespace strata::server {

class ReactorInbox {
public:
    /// A worker's answer for connection `conn`; `close`: close after writing it.
    struct Completion {
        uint64_t conn;
        Outcome outcome;
        bool close;
    };

    ReactorInbox();
    ~ReactorInbox();
    ReactorInbox(const ReactorInbox&) = delete;
    ReactorInbox& operator=(const ReactorInbox&) = delete;

    /// The eventfd to watch for reads; an error when it could not be made.
    Result<int> fd() const;
    /// Thread-safe; each wakes the front end.
    void post(Completion&& done);
    void post_stream(uint64_t conn);
    void wake();
    /// On the front end's thread: empties the eventfd after epoll reported it.
    void clear_wake();
    std::vector<Completion> take_completions();
    std::vector<uint64_t> take_streams();

private:
    int m_fd = -1;
    int m_error = 0;  ///< errno of a failed eventfd()
    std::mutex m_mutex;
    std::vector<Completion> m_done;
    std::vector<uint64_t> m_streams;
};

}  // namespace strata::server

#pragma once
// What the replica's parts (log_reader.h, log_writer.h, snapshot_writer.h) share: how they talk
// to Redis (timeouts, back-off) and how they read its answers.

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

#include "engine/core/result.h"

namespace strata::replica {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

inline constexpr milliseconds CONNECT_TIMEOUT{1000};
inline constexpr milliseconds BACKOFF_FIRST{50};
inline constexpr milliseconds BACKOFF_MAX{2000};

inline int64_t unix_ms() {
    return std::chrono::duration_cast<milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

inline bool parse_u64(std::string_view s, uint64_t& out) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size();
}

/// "123-0" -> 123.
inline bool parse_entry_version(std::string_view id, uint64_t& v) {
    const std::size_t dash = id.find('-');
    return dash != std::string_view::npos && parse_u64(id.substr(0, dash), v);
}

inline Unexpected<Error> storage(std::string message) {
    return failure(ErrorCode::Storage, std::move(message));
}

/// What is left of the time until `deadline`; none once it has passed.
inline milliseconds time_left(Clock::time_point deadline) {
    return std::max(milliseconds(0),
                    std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
}

}  // namespace strata::replica

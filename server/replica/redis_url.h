#pragma once
// `--log redis://HOST:PORT/STREAM`: where a replica's shared edit log lives.

#include <cstdint>
#include <string>
#include <string_view>

#include "engine/core/result.h"

namespace strata::replica {

/// A parsed log address. The stream's companion keys are derived from its name.
struct RedisUrl {
    std::string host;
    int port = 6379;
    std::string stream;

    /// The key holding the version of the stream's last entry (kept by the append script).
    std::string version_key() const { return stream + ":version"; }
    /// The hash holding the newest snapshot (fields "version" and "bytes").
    std::string snapshot_key() const { return stream + ":snapshot"; }
    /// redis://host:port/stream again, for logs and problems.
    std::string describe() const;
};

/// Parses `redis://HOST[:PORT]/STREAM`. HOST may be a name, an IPv4 address or a bracketed IPv6
/// address; PORT defaults to 6379; STREAM is one path segment of printable ASCII without spaces.
/// Errors (InvalidArgument) say which part is wrong.
Result<RedisUrl> parse_redis_url(std::string_view url);

}  // namespace strata::replica

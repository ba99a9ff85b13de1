#pragma once
// The one place that talks to hiredis (libhiredis 0.14, RESP2): a blocking connection with
// connect and command timeouts, replies turned into plain values, Lua scripts run by EVALSHA.
// A connection is used by one thread at a time; once an I/O error happened it is broken for
// good and the caller makes a new one.

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"
#include "server/replica/redis_url.h"

struct redisContext;

namespace strata::replica {

/// A Redis reply as plain data.
struct RedisReply {
    enum class Type : uint8_t { Nil, String, Integer, Array, Status } type = Type::Nil;
    std::string str;  ///< String and Status
    long long integer = 0;
    std::vector<RedisReply> elements;  ///< Array

    bool is_nil() const { return type == Type::Nil; }
};

class RedisConnection {
public:
    /// Connects to `url`'s server. Errors (Storage) name the address and the cause.
    static Result<std::unique_ptr<RedisConnection>> connect(
        const RedisUrl& url, std::chrono::milliseconds connect_timeout,
        std::chrono::milliseconds command_timeout);
    ~RedisConnection();
    RedisConnection(const RedisConnection&) = delete;
    RedisConnection& operator=(const RedisConnection&) = delete;

    /// Runs one command. A Redis error reply and an I/O error are both Storage errors; after an
    /// I/O error (or a timeout) broken() is true.
    Result<RedisReply> command(const std::vector<std::string_view>& args);

    /// Runs a Lua script by EVALSHA, loading it first (SCRIPT LOAD) when this connection has not
    /// yet or the server forgot it (NOSCRIPT after a restart).
    Result<RedisReply> eval(const std::string& script, const std::vector<std::string_view>& keys,
                            const std::vector<std::string_view>& args);

    bool broken() const { return m_broken; }

private:
    RedisConnection(redisContext* context, std::string address);
    Result<RedisReply> run(const std::vector<std::string_view>& args);

    redisContext* m_context;
    std::string m_address;
    bool m_broken = false;
    std::map<std::string, std::string> m_script_shas;  ///< script text -> its SHA1
};

}  // namespace strata::replica

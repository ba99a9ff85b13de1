#include "server/replica/redis_connection.h"

#include <sys/time.h>

#include <hiredis/hiredis.h>

namespace strata::replica {

namespace {

timeval to_timeval(std::chrono::milliseconds ms) {
    timeval tv{};
    tv.tv_sec = static_cast<time_t>(ms.count() / 1000);
    tv.tv_usec = static_cast<suseconds_t>((ms.count() % 1000) * 1000);
    return tv;
}

RedisReply convert(const redisReply* r) {
    RedisReply out;
    switch (r->type) {
        case REDIS_REPLY_STRING:
            out.type = RedisReply::Type::String;
            out.str.assign(r->str, r->len);
            break;
        case REDIS_REPLY_STATUS:
            out.type = RedisReply::Type::Status;
            out.str.assign(r->str, r->len);
            break;
        case REDIS_REPLY_INTEGER:
            out.type = RedisReply::Type::Integer;
            out.integer = r->integer;
            break;
        case REDIS_REPLY_ARRAY:
            out.type = RedisReply::Type::Array;
            out.elements.reserve(r->elements);
            for (std::size_t i = 0; i < r->elements; ++i)
                out.elements.push_back(convert(r->element[i]));
            break;
        default:
            out.type = RedisReply::Type::Nil;
            break;
    }
    return out;
}

}  // namespace

RedisConnection::RedisConnection(redisContext* context, std::string address)
    : m_context(context), m_address(std::move(address)) {}

RedisConnection::~RedisConnection() {
    if (m_context) redisFree(m_context);
}

Result<std::unique_ptr<RedisConnection>> RedisConnection::connect(
    const RedisUrl& url, std::chrono::milliseconds connect_timeout,
    std::chrono::milliseconds command_timeout) {
    redisContext* c =
        redisConnectWithTimeout(url.host.c_str(), url.port, to_timeval(connect_timeout));
    const std::string address = url.host + ":" + std::to_string(url.port);
    if (c == nullptr)
        return failure(ErrorCode::Storage, "cannot connect to Redis at " + address +
                                               ": out of memory for the connection");
    if (c->err) {
        const std::string why = c->errstr;
        redisFree(c);
        return failure(ErrorCode::Storage, "cannot connect to Redis at " + address + ": " + why);
    }
    const timeval tv = to_timeval(command_timeout);
    redisSetTimeout(c, tv);
    redisEnableKeepAlive(c);
    return std::unique_ptr<RedisConnection>(new RedisConnection(c, address));
}

Result<RedisReply> RedisConnection::run(const std::vector<std::string_view>& args) {
    if (m_broken)
        return failure(ErrorCode::Storage, "the connection to Redis at " + m_address + " is lost");
    std::vector<const char*> argv;
    std::vector<std::size_t> lengths;
    argv.reserve(args.size());
    lengths.reserve(args.size());
    for (std::string_view a : args) {
        argv.push_back(a.data());
        lengths.push_back(a.size());
    }
    void* raw = redisCommandArgv(m_context, int(argv.size()), argv.data(), lengths.data());
    auto* reply = static_cast<redisReply*>(raw);
    if (reply == nullptr) {
        m_broken = true;
        return failure(ErrorCode::Storage, "Redis at " + m_address + ": " +
                                               (m_context->err ? std::string(m_context->errstr)
                                                               : std::string("no reply")));
    }
    if (reply->type == REDIS_REPLY_ERROR) {
        std::string why(reply->str, reply->len);
        freeReplyObject(reply);
        return failure(ErrorCode::Storage, "Redis at " + m_address + " answered: " + why);
    }
    RedisReply out = convert(reply);
    freeReplyObject(reply);
    return out;
}

Result<RedisReply> RedisConnection::command(const std::vector<std::string_view>& args) {
    return run(args);
}

Result<RedisReply> RedisConnection::eval(const std::string& script,
                                         const std::vector<std::string_view>& keys,
                                         const std::vector<std::string_view>& args) {
    for (int attempt = 0; attempt < 2; ++attempt) {
        auto sha = m_script_shas.find(script);
        if (sha == m_script_shas.end()) {
            auto loaded = run({"SCRIPT", "LOAD", script});
            if (!loaded) return loaded;
            if (loaded.value().type != RedisReply::Type::String)
                return failure(ErrorCode::Storage,
                               "Redis at " + m_address + ": SCRIPT LOAD answered no SHA1");
            sha = m_script_shas.emplace(script, loaded.value().str).first;
        }
        const std::string count = std::to_string(keys.size());
        std::vector<std::string_view> argv{"EVALSHA", sha->second, count};
        argv.insert(argv.end(), keys.begin(), keys.end());
        argv.insert(argv.end(), args.begin(), args.end());
        auto reply = run(argv);
        if (!reply && !m_broken && reply.error().message.find("NOSCRIPT") != std::string::npos) {
            m_script_shas.erase(sha);  // the server restarted and forgot it: load it again
            continue;
        }
        return reply;
    }
    return failure(ErrorCode::Storage, "Redis at " + m_address + " keeps forgetting a script");
}

}  // namespace strata::replica

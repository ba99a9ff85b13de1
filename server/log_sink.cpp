#include "server/log_sink.h"

#include <spdlog/sinks/stdout_color_sinks.h>

#include "protocol/safe_text.h"

namespace strata::server {

void SafeTextSink::sink_it_(const spdlog::details::log_msg& msg) {
    const std::string safe =
        protocol::escape_for_log(std::string_view(msg.payload.data(), msg.payload.size()));
    spdlog::details::log_msg copy = msg;
    copy.payload = spdlog::string_view_t(safe.data(), safe.size());
    m_inner->log(copy);
}

std::shared_ptr<spdlog::logger> make_safe_logger(const std::string& name) {
    auto sink =
        std::make_shared<SafeTextSink>(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
    return std::make_shared<spdlog::logger>(name, std::move(sink));
}

}  // namespace strata::server

#pragma once
// The server's logger: every record passes through escape_for_log (protocol/safe_text.h) on its
// way to the real sink, so no text a client sent (a path, an id, an exception message quoting a
// header) can break a record in two, forge another, or put invalid UTF-8 into the log.

#include <memory>
#include <string>

#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>

namespace strata::server {

/// Forwards records to `inner` with their message made safe for one log line.
class SafeTextSink : public spdlog::sinks::base_sink<std::mutex> {
public:
    explicit SafeTextSink(spdlog::sink_ptr inner) : m_inner(std::move(inner)) {}

protected:
    void sink_it_(const spdlog::details::log_msg& msg) override;
    void flush_() override { m_inner->flush(); }
    // The inner sink formats the record: patterns and formatters go to it.
    void set_pattern_(const std::string& pattern) override { m_inner->set_pattern(pattern); }
    void set_formatter_(std::unique_ptr<spdlog::formatter> f) override {
        m_inner->set_formatter(std::move(f));
    }

private:
    spdlog::sink_ptr m_inner;
};

/// A logger named `name` writing safe records to stderr (colours when it is a terminal).
std::shared_ptr<spdlog::logger> make_safe_logger(const std::string& name);

}  // namespace strata::server

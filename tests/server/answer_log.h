#pragma once
// The answers in-process HTTP tests see, written down so that tests/server/check_answers.py can
// hold each to the server's OpenAPI description, as tests/python/strata_process.py does for the
// process suites.
//
// With STRATA_ANSWER_LOG set to a directory (ctest sets it; tests/server/CMakeLists.txt), each
// TestServer writes one file there: its own GET /v1/openapi.json on the first line, then one line
// per answer its clients got (method, target, status, media type, and the body when it is JSON).

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>

#include <unistd.h>

#include "protocol/json_document.h"

namespace strata::server::test {

class AnswerLog {
public:
    /// The log of one server, in the directory STRATA_ANSWER_LOG names; null when it is not set.
    static std::unique_ptr<AnswerLog> from_environment() {
        const char* dir = std::getenv("STRATA_ANSWER_LOG");
        if (dir == nullptr || *dir == '\0') return nullptr;
        return std::make_unique<AnswerLog>(dir);
    }

    /// A log file in `dir`, named after this process and a counter.
    explicit AnswerLog(const std::string& dir) {
        static std::atomic<int> serial{0};
        m_path = dir + "/" + std::to_string(::getpid()) + "-" + std::to_string(serial++) + ".jsonl";
        m_out.open(m_path, std::ios::binary | std::ios::trunc);
    }

    /// The first line: the description the answers are checked against.
    void description(const std::string& openapi_json) {
        protocol::Json doc = protocol::Json::parse(openapi_json, nullptr, false);
        std::lock_guard lock(m_mutex);
        m_out << doc.dump() << '\n' << std::flush;
    }

    /// One answer. Bodies that are not JSON are kept as their length: the check reads only their
    /// media type.
    void answer(const std::string& method, const std::string& target, int status,
                const std::string& content_type, const std::string& body) {
        protocol::Json line = {{"method", method},
                               {"target", target},
                               {"status", status},
                               {"content_type", content_type},
                               {"bytes", body.size()}};
        const bool json = content_type.find("json") != std::string::npos;
        line["body"] = json ? body : std::string();
        std::lock_guard lock(m_mutex);
        m_out << line.dump(-1, ' ', false, protocol::Json::error_handler_t::replace) << '\n'
              << std::flush;
    }

    const std::string& path() const { return m_path; }

private:
    std::string m_path;
    std::mutex m_mutex;
    std::ofstream m_out;
};

}  // namespace strata::server::test

#pragma once
// An HttpTransport to an in-process TestServer whose answers go to the server's AnswerLog (when
// answers are recorded; tests/server/answer_log.h).

#include <string>

#include "clients/cli/http_transport.h"
#include "tests/server/test_server.h"

namespace strata::cli::test {

inline HttpOptions options_for(const server::test::TestServer& srv, int timeout_s = 60) {
    HttpOptions options;
    options.url = "http://127.0.0.1:" + std::to_string(srv.port());
    options.timeout_s = timeout_s;
    if (auto log = srv.answers()) {
        options.on_answer = [log](const char* method, const std::string& target, const Reply& r) {
            if (r.status != 0) log->answer(method, target, r.status, r.content_type, r.body);
        };
    }
    return options;
}

}  // namespace strata::cli::test

// The server's log sink: whatever a record quotes from a request, it stays one safe line.

#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include "server/log_sink.h"

namespace strata::server {
namespace {

TEST(SafeTextSink, ARecordQuotingAClientCannotForgeAnotherRecord) {
    std::ostringstream out;
    auto sink =
        std::make_shared<SafeTextSink>(std::make_shared<spdlog::sinks::ostream_sink_mt>(out));
    spdlog::logger logger("test", sink);
    logger.set_pattern("%l %v");
    logger.info("GET {} 404", "/a\r\ninfo forged \xFF");
    logger.flush();
    EXPECT_EQ(out.str(), "info GET /a\\x0d\\x0ainfo forged \\xff 404\n");
}

}  // namespace
}  // namespace strata::server

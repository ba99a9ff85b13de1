// What `strata play` prints: table rows, the readable diff of a failure, the progress bar only
// when asked for, and JSON Lines for scripts.

#include <sstream>

#include <gtest/gtest.h>

#include "clients/cli/play_output.h"
#include "tests/cli/fake_transport.h"

namespace strata::cli {
namespace {

using test::FakeTransport;

struct Printed {
    std::string out, err;
    PlayResult result;
};

Printed play_printed(const std::string& text, bool json, TableOptions table = {false, false}) {
    table.rows = true;
    std::istringstream in(text);
    auto script = load_script(in, "demo.jsonl");
    EXPECT_TRUE(script.has_value()) << (script.has_value() ? "" : script.error().describe());
    FakeTransport fake;
    fake.tlas_actions = {"update", "update", "update", "none"};
    std::ostringstream out, err;
    Printed p;
    if (json) {
        JsonObserver o(out);
        p.result = play(script.value(), fake, PlayOptions{}, o);
    } else {
        TableObserver o(out, err, "the fake", table);
        p.result = play(script.value(), fake, PlayOptions{}, o);
    }
    p.out = out.str();
    p.err = err.str();
    return p;
}

const char* FAILING =
    R"({"edits": [{"op": "clear"}]})"
    "\n"
    R"({"repeat": 4, "steps": [{"commit": {}, "label": "frame", "expect": {"tlas": "update", "rebuilt": ["ball"]}}]})";

TEST(PlayOutput, TheTableHasOneRowPerStepAndTheVerdict) {
    const Printed p =
        play_printed(R"({"edits": [{"op": "clear"}]})"
                     "\n"
                     R"({"repeat": 2, "steps": [{"commit": {}, "expect": {"tlas": "update"}}]})",
                     false);
    std::istringstream lines(p.out);
    std::string line;
    std::getline(lines, line);
    EXPECT_EQ(line, "playing demo.jsonl on the fake (3 steps)");
    std::getline(lines, line);
    EXPECT_EQ(line.rfind(" step  line  kind", 0), 0u);
    std::getline(lines, line);
    EXPECT_NE(line.find("edits"), std::string::npos);
    EXPECT_NE(line.find("1 edit"), std::string::npos);
    std::getline(lines, line);
    EXPECT_NE(line.find("commit  n=0"), std::string::npos) << line;
    EXPECT_NE(line.find("update(1)"), std::string::npos) << line;
    EXPECT_NE(line.find("0.500  ok (1)"), std::string::npos) << line;
    std::getline(lines, line);
    std::getline(lines, line);
    EXPECT_EQ(line.rfind("PASS  3 steps, 2 expectations met, 0 frames written", 0), 0u) << line;
    EXPECT_EQ(p.err, "");  // no progress bar when not asked for
}

TEST(PlayOutput, AFailureIsADiffNamingTheStepLineAndIteration) {
    const Printed p = play_printed(FAILING, false);
    EXPECT_EQ(p.result.verdict, Verdict::ExpectationFailed);
    const std::string& o = p.out;
    EXPECT_NE(o.find("FAIL  demo.jsonl: step 2 (line 2, n=0) commit \"frame\"\n"),
              std::string::npos)
        << o;
    EXPECT_NE(o.find("  field    expected  actual\n"), std::string::npos) << o;
    EXPECT_NE(o.find("  rebuilt  [ball]    []      missing: ball\n"), std::string::npos) << o;
}

TEST(PlayOutput, TheProgressBarGoesToStderrOnLongPlaysOnly) {
    const std::string long_play = R"({"repeat": 50, "steps": [{"commit": {}}]})";
    Printed p = play_printed(long_play, false, {true, true});
    EXPECT_NE(p.err.find("] 50/50 steps"), std::string::npos);
    EXPECT_NE(p.err.find("\r\033[K"), std::string::npos);  // cleared before rows and the verdict
    p = play_printed(R"({"repeat": 5, "steps": [{"commit": {}}]})", false, {true, true});
    EXPECT_EQ(p.err, "");
}

TEST(PlayOutput, JsonLinesHaveOneObjectPerStepAndTheVerdictLast) {
    const Printed p = play_printed(FAILING, true);
    std::istringstream lines(p.out);
    std::string line;
    std::vector<Json> docs;
    while (std::getline(lines, line)) docs.push_back(Json::parse(line));
    ASSERT_EQ(docs.size(), 2u);  // the edits step, then the verdict
    EXPECT_EQ(docs[0]["kind"], "edits");
    EXPECT_EQ(docs[0]["applied"], 1);
    const Json& verdict = docs[1];
    EXPECT_EQ(verdict["result"], "fail");
    EXPECT_EQ(verdict["failure"]["line"], 2);
    EXPECT_EQ(verdict["failure"]["vars"], "n=0");
    EXPECT_EQ(verdict["failure"]["mismatches"][0]["field"], "rebuilt");
    EXPECT_EQ(verdict["failure"]["report"]["tlas"]["action"], "update");
}

TEST(PlayOutput, ARefusedRequestIsReportedOnStderrAsProblemFields) {
    std::istringstream in(R"({"edits": [{"op": "remove_mesh", "mesh": "rock"}]})");
    auto script = load_script(in, "demo.jsonl");
    FakeTransport fake;
    fake.refuse_edits();
    std::ostringstream out, err;
    TableObserver o(out, err, "the fake", {true, false});
    const PlayResult r = play(script.value(), fake, PlayOptions{}, o);
    EXPECT_EQ(r.verdict, Verdict::RequestFailed);
    EXPECT_NE(err.str().find("strata: demo.jsonl: step 1 (line 1) edits: request failed: 422 "
                             "Unknown id\n  detail:     edit 0"),
              std::string::npos)
        << err.str();
    EXPECT_NE(out.str().find("FAIL   stopped after 0 steps"), std::string::npos) << out.str();
}

}  // namespace
}  // namespace strata::cli

// Playing scripts against a recording transport: repeats and substitutions, frames, the first
// failure stops the play with its step, line and iteration, and the limits of --max-repeat.

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "clients/cli/script_runner.h"
#include "tests/cli/fake_transport.h"

namespace strata::cli {
namespace {

using test::FakeTransport;

/// Counts what the runner tells its observer.
class CountingObserver final : public PlayObserver {
public:
    void on_start(const Script&, std::size_t n) override { total = n; }
    void on_step(const StepRecord& r) override { records.push_back(r); }
    void on_finish(const PlayResult&) override { ++finished; }
    std::size_t total = 0;
    std::vector<StepRecord> records;
    int finished = 0;
};

Script load(const std::string& text) {
    std::istringstream in(text);
    auto s = load_script(in, "test.jsonl");
    EXPECT_TRUE(s.has_value()) << (s.has_value() ? "" : s.error().describe());
    return s.has_value() ? std::move(s.value()) : Script{};
}

class ScriptRunner : public ::testing::Test {
protected:
    void SetUp() override {
        dir =
            std::filesystem::temp_directory_path() /
            ("strata-runner-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
             "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::remove_all(dir);
        options.out_dir = dir;
    }
    void TearDown() override { std::filesystem::remove_all(dir); }

    PlayResult run(const std::string& text) {
        script = load(text);
        return play(script, fake, options, observer);
    }

    std::filesystem::path dir;
    PlayOptions options;
    FakeTransport fake;
    CountingObserver observer;
    Script script;
};

TEST_F(ScriptRunner, RepeatsExpandAndSubstituteTheIterationNumber) {
    const PlayResult r = run(
        R"({"repeat": 3, "steps": [{"edits": [{"op": "set_camera", "eye": ["{n}", 0, "{10 - n}"]}]}, {"commit": {}}]})");
    EXPECT_EQ(r.verdict, Verdict::Passed);
    EXPECT_EQ(r.steps_played, 6u);
    EXPECT_EQ(observer.total, 6u);
    EXPECT_EQ(observer.finished, 1);
    ASSERT_EQ(fake.edit_bodies.size(), 3u);
    for (int n = 0; n < 3; ++n)
        EXPECT_EQ(fake.edit_bodies[n]["edits"][0]["eye"], (Json{n, 0, 10 - n}));
    EXPECT_EQ(fake.commits, 3);
    EXPECT_EQ(observer.records[2].vars, "n=1");
    EXPECT_EQ(observer.records[2].applied, 1u);
    EXPECT_EQ(observer.records[3].version, 2u);
}

TEST_F(ScriptRunner, NestedRepeatsSeeBothVariables) {
    run(R"({"repeat": 2, "var": "a", "steps": [{"repeat": 2, "var": "b", "steps": [{"edits": [{"op": "remove_instance", "instance": "i{a}{b}"}]}]}]})");
    ASSERT_EQ(fake.edit_bodies.size(), 4u);
    EXPECT_EQ(fake.edit_bodies[3]["edits"][0]["instance"], "i11");
    EXPECT_EQ(observer.records[1].vars, "a=0, b=1");
}

TEST_F(ScriptRunner, RenderExpectationsReadTheReportThatCameWithTheFrame) {
    // Another client's commit between the render and any later request must not matter: the
    // runner never asks /v1/stats, it reads the report the render answered with.
    fake.tlas_actions = {"update"};
    const PlayResult r = run(R"({"render": {}, "expect": {"tlas": "update"}})");
    ASSERT_EQ(r.verdict, Verdict::Passed) << r.message;
    EXPECT_EQ(fake.stats_calls, 0);
}

TEST_F(ScriptRunner, ARenderAnswerWithoutItsReportIsARequestFailure) {
    struct NoReport final : public Transport {
        Reply edits(std::string, const std::optional<std::string>&) override { return {}; }
        Reply undo(bool, const std::optional<std::string>&) override { return {}; }
        Reply history(const std::multimap<std::string, std::string>&) override { return {}; }
        Reply commit() override { return {}; }
        Reply plan() override { return {}; }
        Reply render(const std::string&) override {
            Reply r;
            r.status = 200;
            r.content_type = "image/png";
            r.body = "frame";
            return r;
        }
        Reply stats() override { return {}; }
        Reply scene() override { return {}; }
        Reply scene_list(const std::string&,
                         const std::multimap<std::string, std::string>&) override {
            return {};
        }
        Reply scene_object(const std::string&, const std::string&) override { return {}; }
        Reply pick(const std::string&) override { return {}; }
        Reply get_snapshot(std::optional<uint64_t>, const std::optional<std::string>&) override {
            return {};
        }
        Reply put_snapshot(std::string) override { return {}; }
        Reply import_asset(std::string, const std::multimap<std::string, std::string>&) override {
            return {};
        }
        Reply assets(const std::optional<std::string>&) override { return {}; }
        Reply delete_asset(const std::string&) override { return {}; }
        Reply put_asset(const std::string&, std::string,
                        const std::multimap<std::string, std::string>&) override {
            return {};
        }
        std::string describe() const override { return "no report"; }
    } transport;
    script = load(R"({"render": {}})");
    const PlayResult r = play(script, transport, options, observer);
    EXPECT_EQ(r.verdict, Verdict::RequestFailed);
    EXPECT_NE(r.message.find("X-Strata-Report"), std::string::npos) << r.message;
}

TEST_F(ScriptRunner, FramesAreWrittenWhereOutSaysAndTheFormatFollowsTheName) {
    const PlayResult r = run(
        R"({"repeat": 2, "steps": [{"edits": []}, {"render": {"width": 8, "height": 4}, "out": "a/b/f{n:3}.png"}]})"
        "\n"
        R"({"render": {}, "out": "deep.exr"})"
        "\n"
        R"({"render": {}})");
    ASSERT_EQ(r.verdict, Verdict::Passed) << r.message;
    EXPECT_EQ(r.frames_written, 3u);
    std::ifstream f1(dir / "a/b/f001.png");
    std::string content((std::istreambuf_iterator<char>(f1)), {});
    EXPECT_EQ(content, "frame at v2");
    EXPECT_TRUE(std::filesystem::exists(dir / "a/b/f000.png"));
    EXPECT_TRUE(std::filesystem::exists(dir / "deep.exr"));
    ASSERT_EQ(fake.render_bodies.size(), 4u);
    EXPECT_EQ(fake.render_bodies[0], (Json{{"width", 8}, {"height", 4}, {"format", "png"}}));
    EXPECT_EQ(fake.render_bodies[2], (Json{{"format", "exr"}}));
    EXPECT_EQ(fake.render_bodies[3], Json::object());  // not saved: nothing inferred
    EXPECT_EQ(observer.records[3].out, (dir / "a/b/f001.png").string());
    EXPECT_EQ(observer.records[3].bytes, content.size());
    EXPECT_EQ(observer.records[3].version, 2u);
    EXPECT_TRUE(observer.records[3].report.has_value());
}

TEST_F(ScriptRunner, AFormatThatContradictsTheFileNameIsAScriptError) {
    const PlayResult r = run(R"({"render": {"format": "exr"}, "out": "f.png"})");
    EXPECT_EQ(r.verdict, Verdict::ScriptError);
    EXPECT_NE(r.message.find("asks for format \"exr\""), std::string::npos);
    EXPECT_TRUE(fake.render_bodies.empty());
}

TEST_F(ScriptRunner, TheFirstFailedExpectationStopsThePlay) {
    fake.tlas_actions = {"update", "update", "none", "update"};
    const PlayResult r = run(
        R"({"commit": {}, "expect": {"tlas": "update"}})"
        "\n"
        R"({"repeat": 5, "steps": [{"commit": {}, "label": "moved", "expect": {"tlas": "update", "blas_rebuilds": 0}}]})");
    EXPECT_EQ(r.verdict, Verdict::ExpectationFailed);
    EXPECT_EQ(exit_code(r.verdict), 1);
    EXPECT_EQ(fake.commits, 3);  // the failing one, and none after it
    ASSERT_TRUE(r.failed.has_value());
    EXPECT_EQ(r.failed->index, 3u);
    EXPECT_EQ(r.failed->step->line, 2u);
    EXPECT_EQ(r.failed->step->label, "moved");
    EXPECT_EQ(r.failed->vars, "n=1");
    ASSERT_EQ(r.mismatches.size(), 1u);
    EXPECT_EQ(r.mismatches[0].field, "tlas");
    EXPECT_EQ(r.mismatches[0].actual, "none");
    EXPECT_EQ(r.checks_passed, 3u);
    EXPECT_EQ(observer.records.size(), 2u);  // the failed step is not reported as played
}

TEST_F(ScriptRunner, ARefusedRequestStopsThePlayWithStratasAnswer) {
    fake.refuse_edits();
    const PlayResult r = run(R"({"commit": {}})"
                             "\n"
                             R"({"edits": [{"op": "remove_mesh", "mesh": "rock"}]})"
                             "\n"
                             R"({"commit": {}})");
    EXPECT_EQ(r.verdict, Verdict::RequestFailed);
    EXPECT_EQ(exit_code(r.verdict), 3);
    EXPECT_EQ(fake.commits, 1);
    ASSERT_TRUE(r.reply.has_value());
    EXPECT_EQ(r.reply->status, 422);
    EXPECT_EQ(r.failed->step->line, 2u);
    const std::string text = describe_failure(*r.reply);
    EXPECT_NE(text.find("422 Unknown id"), std::string::npos);
    EXPECT_NE(text.find("edit index: 0"), std::string::npos);
    EXPECT_NE(text.find("pointer:    /edits/0/mesh"), std::string::npos);
    EXPECT_EQ(text.find('{'), std::string::npos) << "not raw JSON: " << text;
}

TEST_F(ScriptRunner, APickAsksForItsOnePixelAndChecksTheHit) {
    fake.pick_hit = {{"instance", "b1"}, {"mesh", "ball"}, {"primitive", 3}, {"user_id", 7}};
    const PlayResult r = run(
        R"({"repeat": 2, "steps": [{"pick": {"x": "{n * 10}", "y": 5, "width": 64, "height": 32, "camera": {"fov_y_deg": 30}}, "expect": {"hit.instance": "b1", "hit.user_id": 7, "hit": true}}]})");
    ASSERT_EQ(r.verdict, Verdict::Passed) << r.message;
    EXPECT_EQ(r.checks_passed, 6u);
    ASSERT_EQ(fake.pick_bodies.size(), 2u);
    EXPECT_EQ(fake.pick_bodies[1], Json::parse(R"({"width": 64, "height": 32, "pixels": [[10, 5]],
                                                   "camera": {"fov_y_deg": 30}})"));
    ASSERT_EQ(observer.records.size(), 2u);
    ASSERT_TRUE(observer.records[0].answer.has_value());
    EXPECT_EQ((*observer.records[0].answer)["hit"]["mesh"], "ball");
    EXPECT_FALSE(observer.records[0].report.has_value());

    fake.pick_hit = nullptr;
    const PlayResult missed = run(
        R"({"pick": {"x": 0, "y": 0, "width": 4, "height": 4}, "expect": {"hit.instance": "b1"}})");
    EXPECT_EQ(missed.verdict, Verdict::ExpectationFailed);
    ASSERT_EQ(missed.mismatches.size(), 1u);
    EXPECT_EQ(missed.mismatches[0].actual, "(no hit)");
}

TEST_F(ScriptRunner, AListFollowsEveryCursorWithItsFilter) {
    fake.listed = {"a", "b", "c", "d", "e"};
    const PlayResult r = run(
        R"({"list": "instances", "filter": {"mesh": "rock-{1 + 1}", "visible": false}, "expect": {"count": 5, "ids": ["e", "d", "c", "b", "a"]}})");
    ASSERT_EQ(r.verdict, Verdict::Passed) << r.message;
    ASSERT_EQ(fake.list_queries.size(), 3u) << "pages of two";
    for (const auto& [collection, query] : fake.list_queries) {
        EXPECT_EQ(collection, "instances");
        EXPECT_EQ(query.find("mesh")->second, "rock-2");
        EXPECT_EQ(query.find("visible")->second, "false");
    }
    EXPECT_EQ(fake.list_queries[0].second.count("cursor"), 0u);
    EXPECT_EQ(fake.list_queries[2].second.find("cursor")->second, "4");
    EXPECT_EQ((*observer.records[0].answer)["ids"], Json({"a", "b", "c", "d", "e"}));

    const PlayResult wrong = run(R"({"list": "meshes", "expect": {"count": 4}})");
    EXPECT_EQ(wrong.verdict, Verdict::ExpectationFailed);
    EXPECT_EQ(wrong.mismatches.at(0).actual, "5");
}

TEST_F(ScriptRunner, AnExpressionThatFailsWhilePlayingIsAScriptErrorNamingTheIteration) {
    const PlayResult r = run(
        R"({"repeat": 3, "steps": [{"edits": [{"op": "set_camera", "fov_y_deg": "{60 / (n - 1)}"}]}]})");
    EXPECT_EQ(r.verdict, Verdict::ScriptError);
    EXPECT_EQ(exit_code(r.verdict), 2);
    EXPECT_EQ(r.steps_played, 1u);
    EXPECT_EQ(r.failed->vars, "n=1");
    EXPECT_NE(r.message.find("division by zero"), std::string::npos);
}

TEST_F(ScriptRunner, MaxRepeatCapsEveryRepeatStep) {
    options.max_repeat = 2;
    const std::string text =
        R"({"repeat": 100, "steps": [{"repeat": 50, "var": "i", "steps": [{"commit": {}}]}]})";
    EXPECT_EQ(count_steps(load(text), options), 4u);
    const PlayResult r = run(text);
    EXPECT_EQ(r.steps_played, 4u);
    options.max_repeat.reset();
    EXPECT_EQ(count_steps(load(text), options), 5000u);
}

TEST_F(ScriptRunner, InlineRepeatsInsideEditsAreNotCappedByMaxRepeat) {
    options.max_repeat = 1;
    run(R"({"edits": [{"repeat": 5, "var": "i", "items": [{"op": "remove_instance", "instance": "i{i}"}]}]})");
    ASSERT_EQ(fake.edit_bodies.size(), 1u);
    EXPECT_EQ(fake.edit_bodies[0]["edits"].size(), 5u);
}

TEST_F(ScriptRunner, BudgetsAreCountedAsSkippedOutsideTheBudgetsProfile) {
    const std::string text = R"({"commit": {}, "expect": {"tlas": "none", "max_ms": 0.1}})";
    PlayResult r = run(text);
    EXPECT_EQ(r.verdict, Verdict::Passed);
    EXPECT_EQ(r.budgets_skipped, 1u);
    EXPECT_EQ(r.checks_passed, 1u);
    options.budgets = true;
    r = run(text);  // the fake's commits take 0.5 ms
    EXPECT_EQ(r.verdict, Verdict::ExpectationFailed);
    EXPECT_EQ(r.mismatches.at(0).field, "max_ms");
}

}  // namespace
}  // namespace strata::cli

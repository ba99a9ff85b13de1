#pragma once
// Plays a loaded script on a transport: instantiates each step, sends it, saves frames, checks
// expectations, and stops at the first failure with everything needed to explain it.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "clients/cli/script.h"
#include "clients/cli/transport.h"

namespace strata::cli {

/// How to play.
struct PlayOptions {
    bool budgets = false;                ///< check max_ms and max_primitives_built too
    std::optional<uint64_t> max_repeat;  ///< play at most this many iterations of each repeat step
    std::filesystem::path out_dir;       ///< relative "out" paths resolve here (empty: cwd)
};

/// What one played step did.
struct StepRecord {
    std::size_t index = 0;  ///< 1-based position among the steps played
    const Step* step = nullptr;
    std::string vars;            ///< the iteration variables, "n=3, i=0" ("" outside repeats)
    uint64_t version = 0;        ///< the scene version after (edits) or of (others) the step
    std::size_t applied = 0;     ///< edits: edits applied
    std::optional<Json> report;  ///< commit, plan and render: the rebuild report
    /// pick: {"version", "hit"}; list: {"version", "count", "ids"} (what "expect" checks)
    std::optional<Json> answer;
    std::string out;             ///< render: the file written ("" when not saved)
    std::size_t bytes = 0;       ///< render: image size
    std::size_t checks = 0;      ///< expectation fields checked
    double wall_ms = 0.0;        ///< the step's round trip(s), as the client saw them
};

/// How a play ended.
enum class Verdict : uint8_t {
    Passed,             ///< every step ran and every expectation held (exit 0)
    ExpectationFailed,  ///< a report did not match its "expect" (exit 1)
    ScriptError,        ///< the script is wrong: an expression or a value (exit 2)
    RequestFailed,      ///< Strata refused a request, or was unreachable, or a frame not written
                        ///< (exit 3)
};

/// The process exit code for a verdict.
int exit_code(Verdict v);

/// The outcome of a play.
struct PlayResult {
    Verdict verdict = Verdict::Passed;
    std::size_t steps_played = 0;
    std::size_t frames_written = 0;
    std::size_t checks_passed = 0;    ///< expectation fields that held
    std::size_t budgets_skipped = 0;  ///< budget fields not checked (no --budgets)
    double wall_ms = 0.0;
    // When the play failed:
    std::optional<StepRecord> failed;  ///< the failing step
    std::vector<Mismatch> mismatches;  ///< ExpectationFailed: what did not match
    std::string message;               ///< ScriptError, RequestFailed: what went wrong
    std::optional<Reply> reply;        ///< RequestFailed: Strata's answer, when there was one
};

/// Told about progress while a script plays.
class PlayObserver {
public:
    virtual ~PlayObserver() = default;
    /// Before the first step; `total` is the number of steps the play will run.
    virtual void on_start(const Script& script, std::size_t total) = 0;
    /// After each step that succeeded.
    virtual void on_step(const StepRecord& record) = 0;
    /// Once, at the end.
    virtual void on_finish(const PlayResult& result) = 0;
};

/// Number of steps a play will run (repeats expanded, --max-repeat applied), or nullopt when a
/// repeat count cannot be evaluated (the play then reports it).
std::optional<std::size_t> count_steps(const Script& script, const PlayOptions& options);

/// Plays `script`.
PlayResult play(const Script& script, Transport& transport, const PlayOptions& options,
                PlayObserver& observer);

}  // namespace strata::cli

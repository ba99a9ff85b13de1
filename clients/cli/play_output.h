#pragma once
// What `strata play` prints: a per-step table with a progress bar on long scripts (people), or
// one JSON object per step and one for the verdict (scripts).

#include <chrono>
#include <iosfwd>
#include <string>

#include "clients/cli/script_runner.h"

namespace strata::cli {

/// Output settings.
struct TableOptions {
    bool rows = true;      ///< one row per step (false: --quiet, only the verdict)
    bool progress = true;  ///< a progress bar on stderr, when it is a terminal and the play is long
};

/// The per-step table, the progress bar and the verdict, for people.
class TableObserver final : public PlayObserver {
public:
    TableObserver(std::ostream& out, std::ostream& err, std::string where, TableOptions options);

    void on_start(const Script& script, std::size_t total) override;
    void on_step(const StepRecord& record) override;
    void on_finish(const PlayResult& result) override;

private:
    void draw_progress(bool force);
    void clear_progress();

    std::ostream& m_out;
    std::ostream& m_err;
    std::string m_where;
    TableOptions m_options;
    std::string m_script;
    std::size_t m_total = 0;
    std::size_t m_done = 0;
    bool m_bar = false;        ///< the bar is enabled for this play
    bool m_bar_drawn = false;  ///< the bar is on screen now
    std::chrono::steady_clock::time_point m_last_draw{};
};

/// JSON Lines for scripts: {"step": ...} per step, then {"result": ...}.
class JsonObserver final : public PlayObserver {
public:
    explicit JsonObserver(std::ostream& out) : m_out(out) {}

    void on_start(const Script&, std::size_t) override {}
    void on_step(const StepRecord& record) override;
    void on_finish(const PlayResult& result) override;

private:
    std::ostream& m_out;
};

/// Minimum number of steps for which a progress bar is shown.
constexpr std::size_t PROGRESS_MIN_STEPS = 40;

}  // namespace strata::cli

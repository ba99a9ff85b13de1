#include "clients/cli/play_output.h"

#include <algorithm>
#include <cstdio>
#include <ostream>

namespace strata::cli {

namespace {

std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

/// `text` padded with spaces to `width`, on the right (left-aligned) or on the left.
std::string pad(const std::string& text, std::size_t width, bool left_align = false) {
    if (text.size() >= width) return text;
    const std::string fill(width - text.size(), ' ');
    return left_align ? text + fill : fill + text;
}

std::string human_bytes(std::size_t n) {
    if (n < 10 * 1024) return std::to_string(n) + " B";
    if (n < 10 * 1024 * 1024) return std::to_string(n / 1024) + " KiB";
    return std::to_string(n / (1024 * 1024)) + " MiB";
}

/// "step 14 (line 9, n=3)" and the step's kind and label.
std::string where_in_script(const StepRecord& r) {
    std::string s = "step " + std::to_string(r.index) + " (line " + std::to_string(r.step->line) +
                    (r.vars.empty() ? "" : ", " + r.vars) + ") " + step_kind_name(r.step->kind);
    if (!r.step->label.empty()) s += " \"" + r.step->label + "\"";
    return s;
}

/// "hit b0 (ball)", "no hit" or "3 instances".
std::string answer_note(StepKind kind, const Json& answer) {
    if (kind == StepKind::Pick) {
        const Json& hit = answer["hit"];
        if (!hit.is_object()) return "no hit";
        return "hit " + hit.value("instance", std::string("?")) + " (" +
               hit.value("mesh", std::string("?")) + ")";
    }
    return std::to_string(answer.value("count", uint64_t(0))) + " listed";
}

const char* HEADER =
    " step  line  kind    iteration     version  tlas          rebuilds  refits     prims"
    "        ms  note";

std::string row(const StepRecord& r) {
    std::string line = pad(std::to_string(r.index), 5) + pad(std::to_string(r.step->line), 6) +
                       "  " + pad(step_kind_name(r.step->kind), 6, true) + "  " +
                       pad(r.vars.size() > 12 ? r.vars.substr(0, 11) + "~" : r.vars, 12, true) +
                       pad(std::to_string(r.version), 9) + "  ";
    std::string note;
    if (r.report) {
        const Json& rep = *r.report;
        const Json& tlas = rep["tlas"];
        line += pad(tlas.value("action", std::string("?")) + "(" +
                        std::to_string(tlas.value("instances", uint64_t(0))) + ")",
                    12, true) +
                pad(std::to_string(rep.value("blas_rebuilds", 0)), 10) +
                pad(std::to_string(rep.value("blas_refits", 0)), 8) +
                pad(std::to_string(rep.value("primitives_built", uint64_t(0)) +
                                   rep.value("primitives_refit", uint64_t(0))),
                    10) +
                pad(rep.contains("ms") ? fixed(rep["ms"].get<double>(), 3) : "-", 10);
    } else {
        line += std::string(12 + 10 + 8 + 10 + 10, ' ');
        if (r.step->kind == StepKind::Edits)
            note = std::to_string(r.applied) + (r.applied == 1 ? " edit" : " edits");
    }
    if (r.answer) note = answer_note(r.step->kind, *r.answer);
    if (r.step->kind == StepKind::Render)
        note = r.out.empty() ? human_bytes(r.bytes) + " (not saved)" : r.out;
    if (r.checks)
        note += std::string(note.empty() ? "" : "  ") + "ok (" + std::to_string(r.checks) + ")";
    if (!r.step->label.empty()) note += (note.empty() ? "" : "  ") + r.step->label;
    line += "  " + note;
    while (!line.empty() && line.back() == ' ') line.pop_back();
    return line;
}

Json failure_json(const PlayResult& result) {
    Json f = Json::object();
    if (result.failed) {
        const StepRecord& r = *result.failed;
        f["step"] = r.index;
        f["line"] = r.step->line;
        f["kind"] = step_kind_name(r.step->kind);
        if (!r.vars.empty()) f["vars"] = r.vars;
        if (!r.step->label.empty()) f["label"] = r.step->label;
        if (r.report) f["report"] = *r.report;
        if (r.answer) f["answer"] = *r.answer;
    }
    if (!result.message.empty()) f["message"] = result.message;
    if (!result.mismatches.empty()) {
        f["mismatches"] = Json::array();
        for (const Mismatch& m : result.mismatches)
            f["mismatches"].push_back({{"field", m.field},
                                       {"expected", m.expected},
                                       {"actual", m.actual},
                                       {"note", m.note}});
    }
    if (result.reply) {
        f["status"] = result.reply->status;
        const Json body = Json::parse(result.reply->body, nullptr, false);
        if (result.reply->status == 0) {
            f["error"] = result.reply->error;
        } else if (body.is_object()) {
            f["problem"] = body;
        }
    }
    return f;
}

const char* verdict_name(Verdict v) {
    switch (v) {
        case Verdict::Passed:
            return "pass";
        case Verdict::ExpectationFailed:
            return "fail";
        case Verdict::ScriptError:
            return "script_error";
        case Verdict::RequestFailed:
            return "request_failed";
    }
    return "?";
}

}  // namespace

// --- TableObserver ----------------------------------------------------------------------------

TableObserver::TableObserver(std::ostream& out, std::ostream& err, std::string where,
                             TableOptions options)
    : m_out(out), m_err(err), m_where(std::move(where)), m_options(options) {}

void TableObserver::on_start(const Script& script, std::size_t total) {
    m_script = script.name;
    m_total = total;
    m_bar = m_options.progress && total >= PROGRESS_MIN_STEPS;
    if (m_options.rows) {
        m_out << "playing " << script.name << " on " << m_where << " (" << total
              << (total == 1 ? " step)\n" : " steps)\n") << HEADER << '\n';
        m_out.flush();
    }
    draw_progress(true);
}

void TableObserver::on_step(const StepRecord& record) {
    ++m_done;
    if (!m_options.rows) return draw_progress(false);
    // The bar sits below the rows: take it away, print the row, put it back.
    clear_progress();
    m_out << row(record) << '\n';
    m_out.flush();
    draw_progress(true);
}

void TableObserver::on_finish(const PlayResult& result) {
    clear_progress();
    const std::string seconds = fixed(result.wall_ms / 1000.0, 2) + " s";
    switch (result.verdict) {
        case Verdict::Passed: {
            m_out << "PASS  " << result.steps_played << " steps, " << result.checks_passed
                  << " expectations met, " << result.frames_written << " frames written ("
                  << seconds << ")\n";
            if (result.budgets_skipped)
                m_out << "      " << result.budgets_skipped
                      << " budgets not checked (play with --budgets to check them)\n";
            break;
        }
        case Verdict::ExpectationFailed: {
            const StepRecord& r = *result.failed;
            m_out << "FAIL  " << m_script << ": " << where_in_script(r) << '\n';
            std::size_t w = 5;
            for (const Mismatch& m : result.mismatches) w = std::max(w, m.field.size());
            std::size_t we = 8;
            for (const Mismatch& m : result.mismatches) we = std::max(we, m.expected.size());
            std::size_t wa = 6;
            for (const Mismatch& m : result.mismatches) wa = std::max(wa, m.actual.size());
            m_out << "  " << pad("field", w + 2, true) << pad("expected", we + 2, true)
                  << "actual\n";
            for (const Mismatch& m : result.mismatches) {
                std::string line = "  " + pad(m.field, w + 2, true) +
                                   pad(m.expected, we + 2, true) + pad(m.actual, wa + 2, true) +
                                   m.note;
                while (!line.empty() && line.back() == ' ') line.pop_back();
                m_out << line << '\n';
            }
            m_out << "  (stopped after " << result.steps_played << " steps, " << seconds << ")\n";
            break;
        }
        case Verdict::ScriptError:
        case Verdict::RequestFailed: {
            std::string head = m_script;
            if (result.failed) head += ": " + where_in_script(*result.failed);
            m_err << "strata: " << head << ": " << result.message;
            if (result.reply) m_err << ": " << describe_failure(*result.reply);
            m_err << '\n';
            m_out << (result.verdict == Verdict::ScriptError ? "ERROR" : "FAIL ")
                  << "  stopped after " << result.steps_played << " steps (" << seconds << ")\n";
            break;
        }
    }
    m_out.flush();
}

void TableObserver::draw_progress(bool force) {
    if (!m_bar) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && m_done < m_total && now - m_last_draw < std::chrono::milliseconds(100)) return;
    m_last_draw = now;
    constexpr std::size_t WIDTH = 30;
    const std::size_t filled = m_total ? WIDTH * m_done / m_total : 0;
    m_err << "\r[" << std::string(filled, '#') << std::string(WIDTH - filled, '.') << "] " << m_done
          << "/" << m_total << " steps";
    m_err.flush();
    m_bar_drawn = true;
}

void TableObserver::clear_progress() {
    if (!m_bar_drawn) return;
    m_err << "\r\033[K";
    m_err.flush();
    m_bar_drawn = false;
}

// --- JsonObserver -----------------------------------------------------------------------------

void JsonObserver::on_step(const StepRecord& r) {
    Json j = {{"step", r.index},
              {"line", r.step->line},
              {"kind", step_kind_name(r.step->kind)},
              {"version", r.version},
              {"ms", r.wall_ms}};
    if (!r.vars.empty()) j["vars"] = r.vars;
    if (!r.step->label.empty()) j["label"] = r.step->label;
    if (r.step->kind == StepKind::Edits) j["applied"] = r.applied;
    if (r.report) j["report"] = *r.report;
    if (r.answer) j["answer"] = *r.answer;
    if (r.step->kind == StepKind::Render) {
        j["bytes"] = r.bytes;
        if (!r.out.empty()) j["out"] = r.out;
    }
    if (r.step->expect) j["checks"] = r.checks;
    m_out << j.dump() << '\n';
    m_out.flush();
}

void JsonObserver::on_finish(const PlayResult& result) {
    Json j = {{"result", verdict_name(result.verdict)},    {"steps", result.steps_played},
              {"frames", result.frames_written},           {"checks", result.checks_passed},
              {"budgets_skipped", result.budgets_skipped}, {"ms", result.wall_ms}};
    if (result.verdict != Verdict::Passed) j["failure"] = failure_json(result);
    m_out << j.dump() << '\n';
    m_out.flush();
}

}  // namespace strata::cli

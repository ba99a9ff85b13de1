#include "clients/cli/script_runner.h"

#include "clients/cli/image_files.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <map>

namespace strata::cli {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Items per page a list step asks for (the protocol's largest).
constexpr int LIST_PAGE_SIZE = 10000;

/// Ends the play: thrown by the player, caught once in play().
struct Stop {};

uint64_t repeat_count(uint64_t count, const PlayOptions& options) {
    return options.max_repeat ? std::min(count, *options.max_repeat) : count;
}

std::optional<std::size_t> count_in(const std::vector<Step>& steps, const PlayOptions& options,
                                    Bindings& vars) {
    std::size_t total = 0;
    for (const Step& s : steps) {
        if (s.kind != StepKind::Repeat) {
            ++total;
            continue;
        }
        auto count = s.count->evaluate(vars);
        if (!count) return std::nullopt;
        const uint64_t n = repeat_count(count.value(), options);
        for (uint64_t i = 0; i < n; ++i) {
            vars.push(s.var, double(i));
            auto inner = count_in(s.steps, options, vars);
            vars.pop();
            if (!inner) return std::nullopt;
            total += *inner;
        }
    }
    return total;
}

class Player {
public:
    Player(Transport& transport, const PlayOptions& options, PlayObserver& observer)
        : m_transport(transport), m_options(options), m_observer(observer) {}

    void run(const std::vector<Step>& steps) {
        for (const Step& s : steps) {
            if (s.kind == StepKind::Repeat) {
                run_repeat(s);
            } else {
                run_step(s);
            }
        }
    }

    PlayResult& result() { return m_result; }

private:
    void run_repeat(const Step& s) {
        const uint64_t n = repeat_count(value_of(s, s.count->evaluate(m_vars)), m_options);
        for (uint64_t i = 0; i < n; ++i) {
            m_vars.push(s.var, double(i));
            run(s.steps);
            m_vars.pop();
        }
    }

    void run_step(const Step& s) {
        StepRecord r;
        r.index = m_result.steps_played + 1;
        r.step = &s;
        r.vars = m_vars.describe();
        const auto start = Clock::now();
        switch (s.kind) {
            case StepKind::Edits:
                run_edits(s, r);
                break;
            case StepKind::Commit:
                take_report(r, m_transport.commit());
                break;
            case StepKind::Plan:
                take_report(r, m_transport.plan());
                break;
            case StepKind::Render:
                run_render(s, r);
                break;
            case StepKind::Pick:
                run_pick(s, r);
                break;
            case StepKind::List:
                run_list(s, r);
                break;
            case StepKind::Repeat:
                break;
        }
        r.wall_ms = ms_since(start);
        if (s.expect) check(s, r);
        ++m_result.steps_played;
        m_observer.on_step(r);
    }

    void run_edits(const Step& s, StepRecord& r) {
        Json body = Json::object();
        body["edits"] = value_of(s, s.body->instantiate(m_vars));
        const Reply reply = m_transport.edits(body.dump(), std::nullopt);
        const Json doc = answer_json(r, reply);
        r.version = doc.value("version", uint64_t(0));
        r.applied = doc.value("applied", std::size_t(0));
    }

    void run_render(const Step& s, StepRecord& r) {
        Json body = value_of(s, s.body->instantiate(m_vars));
        std::filesystem::path path;
        if (s.out) {
            const std::string out = value_of(s, s.out->render(m_vars));
            // The file name says the format unless the request does.
            const char* by_name = format_of_file_name(out);
            if (by_name && !body.contains("format")) body["format"] = by_name;
            if (by_name && body["format"] != by_name)
                fail_script(s, "\"out\" is '" + out + "' but the request asks for format " +
                                   body["format"].dump());
            path = std::filesystem::path(out);
            if (path.is_relative() && !m_options.out_dir.empty()) path = m_options.out_dir / path;
        }
        const Reply reply = m_transport.render(body.dump());
        if (!reply.ok()) fail_request(r, reply, "render failed");
        r.bytes = reply.body.size();
        r.version = etag_version(reply).value_or(0);
        if (s.out) write_frame(r, path, reply.body);
        // The report of the render's own commit comes with the frame.
        const std::string header = reply.header("X-Strata-Report");
        if (header.empty()) fail_request(r, reply, "the render answer has no X-Strata-Report");
        try {
            r.report = Json::parse(header);
        } catch (const Json::exception& e) {
            fail_request(r, reply, std::string("X-Strata-Report is not JSON: ") + e.what());
        }
        if (r.report->value("entries_truncated", false) && s.expect && s.expect->names_meshes())
            fail_request(r, {},
                         "the render's report is too long for its header (entries truncated); "
                         "expect mesh lists on a commit step instead");
    }

    /// POST /v1/pick for the step's one pixel; the answer is kept as {"version", "hit"}.
    void run_pick(const Step& s, StepRecord& r) {
        const Json p = value_of(s, s.body->instantiate(m_vars));
        Json body = {{"width", p["width"]},
                     {"height", p["height"]},
                     {"pixels", Json::array({Json::array({p["x"], p["y"]})})}};
        for (const char* key : {"camera", "time"})
            if (p.contains(key)) body[key] = p[key];
        const Json doc = answer_json(r, m_transport.pick(body.dump()));
        const Json hits = doc.value("hits", Json::array());
        if (!hits.is_array() || hits.size() != 1)
            fail_request(r, {}, "the pick answer does not have one hit entry");
        r.version = doc.value("version", uint64_t(0));
        r.answer = Json{{"version", r.version}, {"hit", hits[0]}};
    }

    /// Walks every page of GET /v1/scene/{collection}; the answer is kept as {"version" (the
    /// last page's), "count", "ids" (in listing order)}.
    void run_list(const Step& s, StepRecord& r) {
        std::multimap<std::string, std::string> query;
        query.emplace("limit", std::to_string(LIST_PAGE_SIZE));
        if (s.body) {
            const Json filter = value_of(s, s.body->instantiate(m_vars));
            for (const auto& [key, value] : filter.items())
                query.emplace(key, value.is_string() ? value.get<std::string>() : value.dump());
        }
        Json ids = Json::array();
        while (true) {
            const Json page = answer_json(r, m_transport.scene_list(s.collection, query));
            r.version = page.value("version", uint64_t(0));
            for (const Json& item : page.value("items", Json::array()))
                ids.push_back(item.value("id", std::string()));
            const Json next = page.value("next_cursor", Json(nullptr));
            if (!next.is_string()) break;
            query.erase("cursor");
            query.emplace("cursor", next.get<std::string>());
        }
        r.answer = Json{{"version", r.version}, {"count", ids.size()}, {"ids", std::move(ids)}};
    }

    void write_frame(StepRecord& r, const std::filesystem::path& path, const std::string& bytes) {
        std::error_code ec;
        if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
        std::ofstream file(path, std::ios::binary | std::ios::trunc);
        file.write(bytes.data(), std::streamsize(bytes.size()));
        file.close();
        if (!file) fail_request(r, {}, "cannot write frame '" + path.string() + "'");
        r.out = path.string();
        ++m_result.frames_written;
    }

    void take_report(StepRecord& r, const Reply& reply) {
        r.report = answer_json(r, reply);
        r.version = r.report->value("version", uint64_t(0));
    }

    void check(const Step& s, StepRecord& r) {
        const Json& checked = r.answer ? *r.answer : *r.report;
        auto mismatches = value_of(s, s.expect->check(checked, m_vars, m_options.budgets));
        r.checks = s.expect->count_checks() + (m_options.budgets ? s.expect->count_budgets() : 0);
        if (!m_options.budgets) m_result.budgets_skipped += s.expect->count_budgets();
        if (mismatches.empty()) {
            m_result.checks_passed += r.checks;
            return;
        }
        m_result.verdict = Verdict::ExpectationFailed;
        m_result.mismatches = std::move(mismatches);
        m_result.failed = r;
        throw Stop{};
    }

    /// The JSON of a 2xx answer; any other answer ends the play.
    Json answer_json(StepRecord& r, const Reply& reply) {
        if (!reply.ok()) fail_request(r, reply, "request failed");
        Json doc = Json::parse(reply.body, nullptr, false);
        if (doc.is_discarded() || !doc.is_object())
            fail_request(r, reply, "the answer is not a JSON object");
        return doc;
    }

    template <class T>
    T value_of(const Step& s, Outcome<T>&& o) {
        if (!o) fail_script(s, o.error().message);
        return std::move(o).value();
    }

    [[noreturn]] void fail_script(const Step& s, const std::string& message) {
        StepRecord r;
        r.index = m_result.steps_played + 1;
        r.step = &s;
        r.vars = m_vars.describe();
        m_result.verdict = Verdict::ScriptError;
        m_result.message = message;
        m_result.failed = r;
        throw Stop{};
    }

    [[noreturn]] void fail_request(const StepRecord& r, const Reply& reply,
                                   const std::string& message) {
        m_result.verdict = Verdict::RequestFailed;
        m_result.message = message;
        if (reply.status != 0 || !reply.error.empty()) m_result.reply = reply;
        m_result.failed = r;
        throw Stop{};
    }

    Transport& m_transport;
    const PlayOptions& m_options;
    PlayObserver& m_observer;
    Bindings m_vars;
    PlayResult m_result;
};

}  // namespace

int exit_code(Verdict v) {
    switch (v) {
        case Verdict::Passed:
            return 0;
        case Verdict::ExpectationFailed:
            return 1;
        case Verdict::ScriptError:
            return 2;
        case Verdict::RequestFailed:
            return 3;
    }
    return 3;
}

std::optional<std::size_t> count_steps(const Script& script, const PlayOptions& options) {
    Bindings vars;
    return count_in(script.steps, options, vars);
}

PlayResult play(const Script& script, Transport& transport, const PlayOptions& options,
                PlayObserver& observer) {
    const auto start = Clock::now();
    observer.on_start(script, count_steps(script, options).value_or(0));
    Player player(transport, options, observer);
    try {
        player.run(script.steps);
    } catch (const Stop&) {
    }
    PlayResult result = std::move(player.result());
    result.wall_ms = ms_since(start);
    observer.on_finish(result);
    return result;
}

}  // namespace strata::cli

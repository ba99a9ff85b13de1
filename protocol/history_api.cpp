// POST /v1/undo, POST /v1/redo and GET /v1/history: the scene's history (engine/scene/
// edit_history.h) over HTTP.

#include <charconv>
#include <chrono>
#include <ctime>
#include <thread>

#include "engine/durable/edit_codec.h"
#include "protocol/api.h"

namespace strata::protocol {

namespace {

constexpr uint32_t DEFAULT_PAGE = 50;
constexpr uint32_t MAX_PAGE = 1000;
/// Tries of an undo without If-Match when other writers keep landing between reading the stack
/// and applying (or a replica has not applied the shared log's newest entries yet): each try
/// takes back whatever is newest then.
constexpr int UNCONDITIONAL_TRIES = 20;

/// RFC 3339 UTC with milliseconds: "2026-11-27T17:02:03.456Z".
std::string rfc3339(int64_t ms) {
    const std::time_t seconds = std::time_t(ms / 1000);
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    char text[40];
    const std::size_t n = std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
    char millis[8];
    std::snprintf(millis, sizeof millis, ".%03dZ", int(ms % 1000));
    return std::string(text, n) + millis;
}

Json entry_json(const HistoryEntry& e, bool undoable) {
    Json ops = Json::object();
    for (const auto& [kind, n] : e.ops) ops[durable::edit_kind_name(kind)] = n;
    Json j = {{"version", e.version},           {"time", rfc3339(e.info.time_ms)},
              {"kind", batch_kind_name(e.info.kind)}, {"edits", e.edits},
              {"ops", std::move(ops)},          {"undoable", undoable}};
    if (e.info.kind != BatchKind::Edits) j["target"] = e.info.target;
    if (!e.info.message.empty()) j["message"] = e.info.message;
    return j;
}

Problem bad_query(const std::string& parameter, std::string message) {
    Problem p = make_problem(ProblemType::InvalidRequest, std::move(message));
    p.pointer = "/" + parameter;
    return p;
}

/// A whole-string unsigned integer within [lo, hi].
std::optional<uint64_t> parse_count(const std::string& text, uint64_t lo, uint64_t hi) {
    uint64_t n = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size() || n < lo || n > hi)
        return std::nullopt;
    return n;
}

}  // namespace

const char* batch_kind_name(BatchKind kind) {
    switch (kind) {
        case BatchKind::Undo:
            return "undo";
        case BatchKind::Redo:
            return "redo";
        case BatchKind::Edits:
            break;
    }
    return "edit";
}

ApiResponse post_undo(Engine& engine, bool redo, std::optional<std::string_view> if_match,
                      const BatchApply* apply) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return problem_response(problem);

    uint64_t target = 0;
    Result<ApplyResult> applied = failure(ErrorCode::Internal, "not tried");
    for (int attempt = 1;; ++attempt) {
        const uint64_t at = condition->version.value_or(engine.version());
        auto batch = redo ? engine.redo_batch(at) : engine.undo_batch(at);
        if (batch) {
            target = batch.value().info.target;
            applied = apply ? (*apply)(std::move(batch.value()), at)
                            : engine.apply(std::move(batch.value()), at);
        } else {
            applied = Unexpected(std::move(batch).error());
        }
        const bool raced = !applied && applied.error().code == ErrorCode::VersionMismatch;
        if (!raced || condition->version || attempt == UNCONDITIONAL_TRIES) break;
        // A replica may be a few entries behind the shared log: give it time to catch up
        // (about 0.2 s over all tries).
        std::this_thread::sleep_for(std::chrono::milliseconds(attempt));
    }
    if (!applied) {
        const Error& e = applied.error();
        if (e.code == ErrorCode::VersionMismatch)
            return with_etag(problem_response(make_problem(ProblemType::VersionMismatch,
                                                           "If-Match: " + e.message)),
                             engine.version());
        if (e.code == ErrorCode::NothingToUndo)
            return with_etag(problem_response(make_problem(ProblemType::NothingToUndo, e.message)),
                             engine.version());
        // The journal or the edit log could not take it: nothing was applied (503).
        if (e.code == ErrorCode::Storage) return problem_response(problem_from(e));
        // The inverse was valid when it was made; the scene's rules (a budget lowered since a
        // restart) may refuse it now.
        Problem p = problem_from(e);
        p.detail = std::string(redo ? "the redo of version " : "the undo of version ") +
                   std::to_string(target) + " no longer applies: " + e.describe();
        p.pointer.reset();
        p.edit_index = Error::NO_INDEX;
        return problem_response(p);
    }
    const ApplyResult& done = applied.value();
    return with_etag(json_response(200, {{"version", done.version},
                                         {redo ? "redone" : "undone", target},
                                         {"applied", done.applied}}),
                     done.version);
}

std::optional<int64_t> parse_rfc3339(std::string_view text) {
    // YYYY-MM-DDTHH:MM:SS[.fraction](Z|+HH:MM|-HH:MM); 't' and 'z' as RFC 3339 allows.
    const auto digits = [&](std::size_t at, std::size_t n, int& out) {
        if (at + n > text.size()) return false;
        out = 0;
        for (std::size_t i = at; i < at + n; ++i) {
            if (text[i] < '0' || text[i] > '9') return false;
            out = out * 10 + (text[i] - '0');
        }
        return true;
    };
    int year, month, day, hour, minute, second;
    if (!digits(0, 4, year) || text.size() < 20 || text[4] != '-' || !digits(5, 2, month) ||
        text[7] != '-' || !digits(8, 2, day) || (text[10] != 'T' && text[10] != 't') ||
        !digits(11, 2, hour) || text[13] != ':' || !digits(14, 2, minute) || text[16] != ':' ||
        !digits(17, 2, second))
        return std::nullopt;
    if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 || second > 60)
        return std::nullopt;
    std::size_t at = 19;
    int64_t millis = 0;
    if (at < text.size() && text[at] == '.') {
        std::size_t n = 0;
        for (++at; at < text.size() && text[at] >= '0' && text[at] <= '9'; ++at, ++n)
            if (n < 3) millis = millis * 10 + (text[at] - '0');
        if (n == 0) return std::nullopt;
        for (; n < 3; ++n) millis *= 10;
    }
    int64_t offset_minutes = 0;
    if (at < text.size() && (text[at] == 'Z' || text[at] == 'z')) {
        ++at;
    } else if (at < text.size() && (text[at] == '+' || text[at] == '-')) {
        int oh, om;
        if (!digits(at + 1, 2, oh) || at + 3 >= text.size() || text[at + 3] != ':' ||
            !digits(at + 4, 2, om) || oh > 23 || om > 59)
            return std::nullopt;
        offset_minutes = (text[at] == '-' ? -1 : 1) * (oh * 60 + om);
        at += 6;
    } else {
        return std::nullopt;
    }
    if (at != text.size()) return std::nullopt;
    std::tm utc{};
    utc.tm_year = year - 1900;
    utc.tm_mon = month - 1;
    utc.tm_mday = day;
    utc.tm_hour = hour;
    utc.tm_min = minute;
    utc.tm_sec = std::min(second, 59);
    const std::time_t seconds = timegm(&utc);
    if (utc.tm_mday != day) return std::nullopt;  // 2026-02-31 rolled over
    return (int64_t(seconds) - offset_minutes * 60) * 1000 + millis;
}

Parsed<uint64_t> version_at_time(const Engine& engine, std::string_view text) {
    const auto problem = [](std::string why) {
        Problem p = make_problem(ProblemType::NotFound, "at_time: " + std::move(why));
        p.pointer = "/at_time";
        return Unexpected(std::move(p));
    };
    const std::optional<int64_t> ms = parse_rfc3339(text);
    if (!ms) {
        Problem p = make_problem(ProblemType::InvalidRequest,
                                 "at_time must be an RFC 3339 time such as "
                                 "2026-11-27T17:02:03Z or 2026-11-27T18:02:03.5+01:00");
        p.pointer = "/at_time";
        return Unexpected(std::move(p));
    }
    // The newest version made at or before the time, from the history's list (newest first).
    uint64_t before = 0;
    int64_t oldest_ms = 0;
    uint64_t oldest = 0;
    for (;;) {
        const HistoryPage page = engine.history(MAX_PAGE, before);
        for (const HistoryEntry& e : page.entries) {
            if (e.info.time_ms <= *ms) return e.version;
            oldest = e.version;
            oldest_ms = e.info.time_ms;
        }
        if (page.entries.size() < MAX_PAGE) break;
        before = page.entries.back().version;
    }
    if (oldest == 0)
        return problem("the history lists no version since the scene was loaded, so none can be "
                       "found by time (at_version works with the data directory)");
    return problem("the oldest version the history lists, " + std::to_string(oldest) +
                   ", was made at " + rfc3339(oldest_ms) + ", after " + std::string(text));
}

ApiResponse get_history(const Engine& engine,
                        const std::multimap<std::string, std::string>& query) {
    uint32_t limit = DEFAULT_PAGE;
    uint64_t before = 0;
    for (const auto& [key, text] : query) {
        if (query.count(key) > 1)
            return problem_response(
                bad_query(key, "query parameter '" + key + "' is given more than once"));
        if (key == "limit") {
            const auto n = parse_count(text, 1, MAX_PAGE);
            if (!n)
                return problem_response(bad_query(
                    key, "limit must be an integer from 1 to " + std::to_string(MAX_PAGE)));
            limit = uint32_t(*n);
        } else if (key == "cursor") {
            const auto n = parse_count(text, 1, UINT64_MAX);
            if (!n)
                return problem_response(bad_query(
                    key, "cursor must be a positive integer: a next_cursor of an earlier page"));
            before = *n;
        } else {
            return problem_response(
                bad_query(key, "unknown query parameter '" + key + "' (known: limit, cursor)"));
        }
    }
    const uint64_t version = engine.version();
    const HistoryPage page = engine.history(limit, before);
    Json entries = Json::array();
    for (std::size_t i = 0; i < page.entries.size(); ++i)
        entries.push_back(entry_json(page.entries[i], page.undoable[i]));
    const auto next_or_null = [](uint64_t v) { return v ? Json(v) : Json(nullptr); };
    Json body = {{"version", version},
                 {"oldest", next_or_null(page.oldest)},
                 {"undo", {{"depth", page.undo_depth}, {"next", next_or_null(page.next_undo)}}},
                 {"redo", {{"depth", page.redo_depth}, {"next", next_or_null(page.next_redo)}}},
                 {"held_bytes", page.held_bytes},
                 {"entries", std::move(entries)}};
    const bool more = !page.entries.empty() && page.entries.size() == limit &&
                      page.entries.back().version > page.oldest;
    body["next_cursor"] = more ? Json(std::to_string(page.entries.back().version)) : Json(nullptr);
    return with_etag(json_response(200, body), version);
}

}  // namespace strata::protocol

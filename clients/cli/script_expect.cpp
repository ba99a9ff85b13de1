#include "clients/cli/script_expect.h"

#include <algorithm>
#include <iterator>
#include <map>

namespace strata::cli {

namespace {

/// Count fields: wire name and where the report keeps it.
struct CountSource {
    const char* name;
    const char* parent;  ///< nullptr: top level
    const char* member;
};
constexpr CountSource COUNT_FIELDS[] = {
    {"version", nullptr, "version"},
    {"tlas_instances", "tlas", "instances"},
    {"tlas_static_instances", "tlas", "static_instances"},
    {"tlas_dynamic_instances", "tlas", "dynamic_instances"},
    {"tlas_stale_copies", "tlas", "stale_copies"},
    {"instances_changed", nullptr, "instances_changed"},
    {"blas_rebuilds", nullptr, "blas_rebuilds"},
    {"blas_refits", nullptr, "blas_refits"},
    {"primitives_built", nullptr, "primitives_built"},
    {"primitives_refit", nullptr, "primitives_refit"},
    {"clusters_rebuilt", nullptr, "clusters_rebuilt"},
    {"clusters_refit", nullptr, "clusters_refit"},
};

/// The fields of a pick or list step's expectation and where its answer keeps them.
enum class AnswerType : uint8_t { Count, Text, IdSet, Hit };
struct AnswerField {
    const char* name;
    const char* parent;  ///< nullptr: top level
    const char* member;
    AnswerType type;
};
constexpr AnswerField PICK_FIELDS[] = {
    {"version", nullptr, "version", AnswerType::Count},
    {"hit", nullptr, "hit", AnswerType::Hit},
    {"hit.instance", "hit", "instance", AnswerType::Text},
    {"hit.mesh", "hit", "mesh", AnswerType::Text},
    {"hit.primitive", "hit", "primitive", AnswerType::Count},
    {"hit.user_id", "hit", "user_id", AnswerType::Count},
    {"hit.distance", "hit", "distance", AnswerType::Count},
};
constexpr AnswerField LIST_FIELDS[] = {
    {"version", nullptr, "version", AnswerType::Count},
    {"count", nullptr, "count", AnswerType::Count},
    {"ids", nullptr, "ids", AnswerType::IdSet},
};

// Points and curves have no refit (Embree's sphere and curve BVHs are rebuilt), so their position
// edits and refit requests are rebuilds with the refit reasons.
const std::vector<std::string> REBUILD_REASONS = {
    "added",         "topology_changed", "rebuild_requested", "refit_not_allowed",
    "bounds_growth", "triangle_growth",  "refit_limit",       "clustered",
    "shared",        "unshared",         "positions_changed", "refit_requested",
    "keys_changed"};
const std::vector<std::string> REFIT_REASONS = {"positions_changed", "refit_requested",
                                                "triangles_replaced"};
const std::vector<std::string> TLAS_ACTIONS = {"none", "update", "rebuild"};

std::string quoted_list(const std::vector<std::string>& items) {
    std::string out;
    for (const std::string& s : items) out += (out.empty() ? "\"" : ", \"") + s + "\"";
    return out;
}

bool contains(const std::vector<std::string>& list, const std::string& s) {
    return std::find(list.begin(), list.end(), s) != list.end();
}

Outcome<Expression> compile_number(const Json& v, const std::string& field,
                                   const std::vector<std::string>& names) {
    if (v.is_number()) return Expression::constant(v.get<double>());
    if (v.is_string()) {
        auto t = StringTemplate::compile(v.get<std::string>(), names);
        if (!t) return Unexpected(Failure{"expect." + field + ": " + t.error().message});
        if (t.value().is_number()) return t.value().expression();
    }
    return Unexpected(Failure{"expect." + field +
                              ": expected a number or one \"{expression}\", got " + v.dump()});
}

Outcome<CountExpectation> compile_count(const Json& v, const std::string& field,
                                        const std::vector<std::string>& names) {
    CountExpectation c;
    if (!v.is_object()) {
        auto e = compile_number(v, field, names);
        if (!e) return Unexpected(e.error());
        c.exact = std::move(e.value());
        return c;
    }
    if (auto bad = check_members(v, "expect." + field, {"min", "max"})) return Unexpected(*bad);
    if (v.empty())
        return Unexpected(Failure{"expect." + field + ": give \"min\", \"max\" or both"});
    for (const char* bound : {"min", "max"}) {
        if (!v.contains(bound)) continue;
        auto e = compile_number(v[bound], field + "." + bound, names);
        if (!e) return Unexpected(e.error());
        (std::string(bound) == "min" ? c.min : c.max) = std::move(e.value());
    }
    return c;
}

Outcome<MeshSetExpectation> compile_meshes(const Json& v, const std::string& field,
                                           const std::vector<std::string>& names) {
    MeshSetExpectation m;
    auto add_id = [&](const std::string& id) -> std::optional<Failure> {
        auto t = StringTemplate::compile(id, names);
        if (!t) return Failure{"expect." + field + ": " + t.error().message};
        m.ids.push_back(std::move(t.value()));
        return std::nullopt;
    };
    if (v.is_array()) {
        for (const Json& id : v) {
            if (!id.is_string())
                return Unexpected(
                    Failure{"expect." + field + ": mesh ids are strings, got " + id.dump()});
            if (auto bad = add_id(id.get<std::string>())) return Unexpected(*bad);
        }
        return m;
    }
    const std::vector<std::string>* reasons = field == "rebuilt" ? &REBUILD_REASONS
                                              : field == "refit" ? &REFIT_REASONS
                                                                 : nullptr;
    if (!v.is_object() || !reasons)
        return Unexpected(Failure{"expect." + field + ": expected an array of mesh ids" +
                                  std::string(reasons ? " or an object {mesh id: reason}" : "")});
    m.with_reasons = true;
    for (const auto& [id, reason] : v.items()) {
        if (!reason.is_string() || !contains(*reasons, reason.get<std::string>()))
            return Unexpected(Failure{"expect." + field + "." + id + ": expected one of " +
                                      quoted_list(*reasons) + ", got " + reason.dump()});
        if (auto bad = add_id(id)) return Unexpected(*bad);
        m.reasons.push_back(reason.get<std::string>());
    }
    return m;
}

std::string describe_count(const CountExpectation& c, const Bindings& vars,
                           std::optional<double>& lo, std::optional<double>& hi,
                           std::optional<Failure>& error) {
    auto eval = [&](const std::optional<Expression>& e) -> std::optional<double> {
        if (!e) return std::nullopt;
        auto v = e->evaluate(vars);
        if (!v) {
            error = v.error();
            return std::nullopt;
        }
        return v.value();
    };
    if (c.exact) {
        lo = hi = eval(c.exact);
        return lo ? format_number(*lo) : "";
    }
    lo = eval(c.min);
    hi = eval(c.max);
    if (lo && hi) return format_number(*lo) + " to " + format_number(*hi);
    if (lo) return ">= " + format_number(*lo);
    return hi ? "<= " + format_number(*hi) : "";
}

/// id -> reason ("" when reasons are not compared) of a report's entries.
std::map<std::string, std::string> report_meshes(const Json& report, const std::string& field,
                                                 bool with_reasons) {
    std::map<std::string, std::string> out;
    const Json* list = report.contains(field) ? &report[field] : nullptr;
    if (!list || !list->is_array()) return out;
    for (const Json& e : *list) {
        if (e.is_string()) {
            out[e.get<std::string>()] = "";  // released: plain ids
        } else if (e.is_object() && e.contains("mesh")) {
            out[e["mesh"].get<std::string>()] =
                with_reasons && e.contains("reason") ? e["reason"].get<std::string>() : "";
        }
    }
    return out;
}

std::string describe_meshes(const std::map<std::string, std::string>& m, bool with_reasons) {
    if (m.empty()) return with_reasons ? "{}" : "[]";
    std::string out;
    for (const auto& [id, reason] : m)
        out += (out.empty() ? "" : ", ") + id + (with_reasons ? ": " + reason : "");
    return with_reasons ? "{" + out + "}" : "[" + out + "]";
}

/// What a field that is absent from a document reads as, and why.
std::pair<std::string, std::string> absent(const Json& doc, const char* parent) {
    if (parent && doc.contains(parent) && doc[parent].is_null())
        return {"(no " + std::string(parent) + ")", std::string("nothing was ") + parent};
    return {"(absent)", "the answer has no such member"};
}

std::optional<double> number_at(const Json& report, const char* parent, const char* member) {
    const Json* obj = &report;
    if (parent) {
        if (!report.contains(parent)) return std::nullopt;
        obj = &report[parent];
    }
    if (!obj->is_object() || !obj->contains(member) || !(*obj)[member].is_number())
        return std::nullopt;
    return (*obj)[member].get<double>();
}

}  // namespace

Outcome<Expectation> Expectation::compile_answer(const Json& v,
                                                 const std::vector<std::string>& names,
                                                 ExpectTarget target) {
    const bool pick = target == ExpectTarget::Pick;
    const std::vector<AnswerField> fields =
        pick ? std::vector<AnswerField>(std::begin(PICK_FIELDS), std::end(PICK_FIELDS))
             : std::vector<AnswerField>(std::begin(LIST_FIELDS), std::end(LIST_FIELDS));
    std::vector<std::string> allowed;
    for (const AnswerField& f : fields) allowed.push_back(f.name);
    if (auto bad =
            check_members(v, pick ? "\"expect\" of a pick" : "\"expect\" of a list", allowed))
        return Unexpected(*bad);
    Expectation e;
    for (const AnswerField& f : fields) {
        if (!v.contains(f.name)) continue;
        const Json& x = v[f.name];
        switch (f.type) {
            case AnswerType::Count: {
                auto count = compile_count(x, f.name, names);
                if (!count) return Unexpected(count.error());
                e.m_counts.push_back({f.name, std::move(count.value()), f.parent, f.member});
                break;
            }
            case AnswerType::Text: {
                if (!x.is_string())
                    return Unexpected(Failure{std::string("expect.") + f.name +
                                              ": expected an id (a string), got " + x.dump()});
                auto t = StringTemplate::compile(x.get<std::string>(), names);
                if (!t)
                    return Unexpected(
                        Failure{std::string("expect.") + f.name + ": " + t.error().message});
                e.m_texts.push_back({f.name, std::move(t.value()), f.parent, f.member});
                break;
            }
            case AnswerType::IdSet: {
                if (!x.is_array())
                    return Unexpected(Failure{std::string("expect.") + f.name +
                                              ": expected an array of ids, got " + x.dump()});
                auto m = compile_meshes(x, f.name, names);
                if (!m) return Unexpected(m.error());
                e.m_meshes.push_back({f.name, std::move(m.value())});
                break;
            }
            case AnswerType::Hit:
                if (!x.is_boolean())
                    return Unexpected(Failure{std::string("expect.") + f.name +
                                              ": expected true (something is hit) or false, got " +
                                              x.dump()});
                e.m_hit = x.get<bool>();
                break;
        }
    }
    return e;
}

Outcome<Expectation> Expectation::compile(const Json& v, const std::vector<std::string>& names,
                                          bool has_time, ExpectTarget target) {
    if (target != ExpectTarget::Report) return compile_answer(v, names, target);
    std::vector<std::string> allowed = {"tlas",     "rebuilt", "refit",
                                        "released", "max_ms",  "max_primitives_built"};
    for (const CountSource& c : COUNT_FIELDS) allowed.push_back(c.name);
    if (auto bad = check_members(v, "\"expect\"", allowed)) return Unexpected(*bad);
    Expectation e;
    for (const CountSource& c : COUNT_FIELDS) {
        if (!v.contains(c.name)) continue;
        auto count = compile_count(v[c.name], c.name, names);
        if (!count) return Unexpected(count.error());
        e.m_counts.push_back({c.name, std::move(count.value()), c.parent, c.member});
    }
    if (v.contains("tlas")) {
        const Json& t = v["tlas"];
        if (!t.is_string() || !contains(TLAS_ACTIONS, t.get<std::string>()))
            return Unexpected(Failure{"expect.tlas: expected one of " + quoted_list(TLAS_ACTIONS) +
                                      ", got " + t.dump()});
        e.m_tlas = t.get<std::string>();
    }
    for (const char* field : {"rebuilt", "refit", "released"}) {
        if (!v.contains(field)) continue;
        auto m = compile_meshes(v[field], field, names);
        if (!m) return Unexpected(m.error());
        e.m_meshes.push_back({field, std::move(m.value())});
    }
    if (v.contains("max_ms")) {
        if (!has_time) return Unexpected(Failure{"expect.max_ms: a plan takes no time to check"});
        auto x = compile_number(v["max_ms"], "max_ms", names);
        if (!x) return Unexpected(x.error());
        e.m_max_ms = std::move(x.value());
    }
    if (v.contains("max_primitives_built")) {
        auto x = compile_number(v["max_primitives_built"], "max_primitives_built", names);
        if (!x) return Unexpected(x.error());
        e.m_max_primitives_built = std::move(x.value());
    }
    return e;
}

std::size_t Expectation::count_checks() const {
    return m_counts.size() + m_meshes.size() + m_texts.size() + (m_tlas ? 1 : 0) + (m_hit ? 1 : 0) +
           (m_max_primitives_built ? 1 : 0);
}

std::size_t Expectation::count_budgets() const {
    return m_max_ms ? 1 : 0;
}

Outcome<std::vector<Mismatch>> Expectation::check(const Json& report, const Bindings& vars,
                                                  bool budgets) const {
    std::vector<Mismatch> out;
    std::optional<Failure> error;

    // Step 1: counts, exact or within bounds.
    for (const CountField& f : m_counts) {
        std::optional<double> lo, hi;
        const std::string expected = describe_count(f.expect, vars, lo, hi, error);
        if (error) return Unexpected(*error);
        const std::optional<double> actual = number_at(report, f.parent, f.member);
        if (!actual) {
            const auto [what, why] = absent(report, f.parent);
            out.push_back({f.name, expected, what, why});
        } else if ((lo && *actual < *lo) || (hi && *actual > *hi)) {
            out.push_back({f.name, expected, format_number(*actual), ""});
        }
    }

    // Step 1b (pick and list answers): whether anything was hit, and ids.
    if (m_hit) {
        const bool actual = report.contains("hit") && !report["hit"].is_null();
        if (actual != *m_hit)
            out.push_back({"hit", *m_hit ? "true" : "false", actual ? "true" : "false", ""});
    }
    for (const TextField& f : m_texts) {
        auto expected = f.expect.render(vars);
        if (!expected) return Unexpected(expected.error());
        const Json* obj = f.parent && report.contains(f.parent) ? &report[f.parent] : &report;
        if (!obj->is_object() || !obj->contains(f.member) || !(*obj)[f.member].is_string()) {
            const auto [what, why] = absent(report, f.parent);
            out.push_back({f.name, expected.value(), what, why});
        } else if ((*obj)[f.member].get<std::string>() != expected.value()) {
            out.push_back({f.name, expected.value(), (*obj)[f.member].get<std::string>(), ""});
        }
    }

    // Step 2: the TLAS action.
    if (m_tlas) {
        const std::string actual = report.contains("tlas") && report["tlas"].contains("action")
                                       ? report["tlas"]["action"].get<std::string>()
                                       : "(absent)";
        if (actual != *m_tlas) out.push_back({"tlas", *m_tlas, actual, ""});
    }

    // Step 3: the sets of meshes, with reasons when the expectation names them.
    for (const MeshField& f : m_meshes) {
        std::map<std::string, std::string> expected;
        for (std::size_t i = 0; i < f.expect.ids.size(); ++i) {
            auto id = f.expect.ids[i].render(vars);
            if (!id) return Unexpected(id.error());
            expected[id.value()] = f.expect.with_reasons ? f.expect.reasons[i] : "";
        }
        const auto actual = report_meshes(report, f.name, f.expect.with_reasons);
        if (actual == expected) continue;
        std::string missing, unexpected, reasons;
        for (const auto& [id, reason] : expected) {
            const auto it = actual.find(id);
            if (it == actual.end()) {
                missing += (missing.empty() ? "" : ", ") + id;
            } else if (it->second != reason) {
                reasons += (reasons.empty() ? "" : "; ") + id + " was " + it->second;
            }
        }
        for (const auto& [id, reason] : actual)
            if (!expected.count(id)) unexpected += (unexpected.empty() ? "" : ", ") + id;
        std::string note;
        if (!missing.empty()) note += "missing: " + missing;
        if (!unexpected.empty()) note += (note.empty() ? "" : "; ") + ("unexpected: " + unexpected);
        if (!reasons.empty()) note += (note.empty() ? "" : "; ") + reasons;
        out.push_back({f.name, describe_meshes(expected, f.expect.with_reasons),
                       describe_meshes(actual, f.expect.with_reasons), note});
    }

    // Step 4: budgets. A primitive count is deterministic and always checked; wall time only
    // in the budgets profile.
    {
        auto budget = [&](const std::optional<Expression>& limit, const char* field,
                          const char* member) -> std::optional<Failure> {
            if (!limit) return std::nullopt;
            auto max = limit->evaluate(vars);
            if (!max) return max.error();
            const std::optional<double> actual = number_at(report, nullptr, member);
            if (!actual) {
                out.push_back({field, "<= " + format_number(max.value()), "(absent)", ""});
            } else if (*actual > max.value()) {
                out.push_back({field, "<= " + format_number(max.value()), format_number(*actual),
                               "over budget"});
            }
            return std::nullopt;
        };
        if (budgets) {
            if (auto e = budget(m_max_ms, "max_ms", "ms")) return Unexpected(*e);
        }
        if (auto e = budget(m_max_primitives_built, "max_primitives_built", "primitives_built"))
            return Unexpected(*e);
    }
    return out;
}

}  // namespace strata::cli

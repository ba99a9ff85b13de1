// Loading scripts: strict JSON per line, step kinds and members, templates and expectations.

#include <algorithm>
#include <fstream>
#include <iostream>
#include <set>

#include "clients/cli/script.h"

#include "clients/cli/commands.h"

namespace strata::cli {

namespace {

constexpr const char* KIND_KEYS[] = {"edits", "commit", "plan", "render", "repeat", "pick", "list"};

void compile_expect(Step& s, const Json& v, const std::vector<std::string>& names) {
    if (!v.contains("expect")) return;
    const ExpectTarget target = s.kind == StepKind::Pick   ? ExpectTarget::Pick
                                : s.kind == StepKind::List ? ExpectTarget::List
                                                           : ExpectTarget::Report;
    s.expect =
        value_or_throw(Expectation::compile(v["expect"], names, s.kind != StepKind::Plan, target));
}

/// A pick step's object: the GET /v1/pick members (x, y, width, height required; camera,
/// time).
void compile_pick(Step& s, const Json& v, const std::vector<std::string>& names) {
    const Json& p = v["pick"];
    if (!p.is_object())
        throw ScriptFailure{
            "\"pick\" must be an object {\"x\", \"y\", \"width\", \"height\"} "
            "(and optionally \"camera\" and \"time\")"};
    if (auto bad = check_members(p, "\"pick\"", {"x", "y", "width", "height", "camera", "time"}))
        throw ScriptFailure{bad->message};
    for (const char* key : {"x", "y", "width", "height"})
        if (!p.contains(key)) throw ScriptFailure{std::string("\"pick\" needs \"") + key + "\""};
    s.body = value_or_throw(JsonTemplate::compile(p, names));
}

/// A list step: the collection and an optional filter of query parameters.
void compile_list(Step& s, const Json& v, const std::vector<std::string>& names) {
    const std::vector<std::string>& collections = scene_collections();
    const Json& c = v["list"];
    if (!c.is_string() || std::find(collections.begin(), collections.end(), c.get<std::string>()) ==
                              collections.end()) {
        std::string known;
        for (const std::string& k : collections) known += (known.empty() ? "" : ", ") + k;
        throw ScriptFailure{"\"list\" names a collection: one of " + known + ", not " + c.dump()};
    }
    s.collection = c.get<std::string>();
    if (v.contains("filter")) {
        const Json& f = v["filter"];
        if (!f.is_object())
            throw ScriptFailure{
                "\"filter\" must be an object of query parameters, such as "
                "{\"mesh\": \"rock\", \"visible\": true}"};
        for (const auto& [key, value] : f.items()) {
            if (key == "limit" || key == "cursor")
                throw ScriptFailure{"\"filter\" takes no \"" + key +
                                    "\": a list step reads every page itself"};
            if (!value.is_string() && !value.is_boolean() && !value.is_number())
                throw ScriptFailure{"filter." + key + ": expected a string, number or boolean"};
        }
        s.body = value_or_throw(JsonTemplate::compile(f, names));
    }
}

void require_empty_object(const Json& v, const char* key) {
    if (!v[key].is_object() || !v[key].empty())
        throw ScriptFailure{std::string("\"") + key + "\" takes no options: write \"" + key +
                            "\": {}"};
}

Step compile_step(const Json& v, std::size_t line, std::vector<std::string>& names) {
    if (!v.is_object())
        throw ScriptFailure{"a step is a JSON object, not " + std::string(v.type_name())};
    Step s;
    s.line = line;
    const char* kind = nullptr;
    for (std::size_t i = 0; i < std::size(KIND_KEYS); ++i) {
        if (!v.contains(KIND_KEYS[i])) continue;
        if (kind)
            throw ScriptFailure{
                std::string("a step is one of edits, commit, plan, render, repeat, pick or "
                            "list; this one has both \"") +
                kind + "\" and \"" + KIND_KEYS[i] + "\""};
        kind = KIND_KEYS[i];
        s.kind = StepKind(i);
    }
    if (!kind) {
        std::string keys;
        for (const auto& [key, value] : v.items()) keys += (keys.empty() ? "" : ", ") + key;
        throw ScriptFailure{"unknown step (members: " + (keys.empty() ? "none" : keys) +
                            "); a step has one of \"edits\", \"commit\", \"plan\", \"render\", "
                            "\"repeat\", \"pick\" or \"list\""};
    }
    if (v.contains("label")) {
        if (!v["label"].is_string()) throw ScriptFailure{"\"label\" must be a string"};
        s.label = v["label"].get<std::string>();
    }
    switch (s.kind) {
        case StepKind::Edits:
            if (auto bad = check_members(v, "an edits step", {"edits", "label"}))
                throw ScriptFailure{bad->message};
            if (!v["edits"].is_array())
                throw ScriptFailure{"\"edits\" must be an array of edit ops (protocol/README.md)"};
            s.body = value_or_throw(JsonTemplate::compile(v["edits"], names));
            break;
        case StepKind::Commit:
        case StepKind::Plan:
            if (auto bad =
                    check_members(v, std::string("a ") + kind + " step", {kind, "expect", "label"}))
                throw ScriptFailure{bad->message};
            require_empty_object(v, kind);
            compile_expect(s, v, names);
            break;
        case StepKind::Render:
            if (auto bad = check_members(v, "a render step", {"render", "out", "expect", "label"}))
                throw ScriptFailure{bad->message};
            if (!v["render"].is_object())
                throw ScriptFailure{
                    "\"render\" must be a render request object (protocol/README.md)"};
            s.body = value_or_throw(JsonTemplate::compile(v["render"], names));
            if (v.contains("out")) {
                if (!v["out"].is_string() || v["out"].get<std::string>().empty())
                    throw ScriptFailure{"\"out\" must be a file name"};
                s.out = value_or_throw(StringTemplate::compile(v["out"].get<std::string>(), names));
            }
            compile_expect(s, v, names);
            break;
        case StepKind::Pick:
            if (auto bad = check_members(v, "a pick step", {"pick", "expect", "label"}))
                throw ScriptFailure{bad->message};
            compile_pick(s, v, names);
            compile_expect(s, v, names);
            break;
        case StepKind::List:
            if (auto bad = check_members(v, "a list step", {"list", "filter", "expect", "label"}))
                throw ScriptFailure{bad->message};
            compile_list(s, v, names);
            compile_expect(s, v, names);
            break;
        case StepKind::Repeat: {
            if (auto bad = check_members(v, "a repeat step", {"repeat", "var", "steps", "label"}))
                throw ScriptFailure{bad->message};
            s.count = value_or_throw(CountTemplate::compile(v["repeat"], names));
            s.var = "n";
            if (v.contains("var")) {
                if (!v["var"].is_string() || !is_variable_name(v["var"].get<std::string>()))
                    throw ScriptFailure{
                        "\"var\" must be a name such as \"i\" (letters, digits, _)"};
                s.var = v["var"].get<std::string>();
            }
            if (!v.contains("steps") || !v["steps"].is_array() || v["steps"].empty())
                throw ScriptFailure{"a repeat needs \"steps\": a non-empty array of steps"};
            names.push_back(s.var);
            for (const Json& inner : v["steps"])
                s.steps.push_back(compile_step(inner, line, names));
            names.pop_back();
            break;
        }
    }
    return s;
}

/// Strips "[json.exception.parse_error.101] " from nlohmann's messages.
std::string json_message(const std::string& what) {
    const std::size_t close = what.find("] ");
    return close == std::string::npos ? what : what.substr(close + 2);
}

}  // namespace

const char* step_kind_name(StepKind k) {
    return KIND_KEYS[int(k)];
}

Outcome<Json> parse_json_strict(const std::string& text) {
    std::vector<std::set<std::string>> open_objects;
    std::string duplicate;
    auto on_event = [&](int, Json::parse_event_t event, Json& parsed) {
        if (event == Json::parse_event_t::object_start) {
            open_objects.emplace_back();
        } else if (event == Json::parse_event_t::object_end) {
            open_objects.pop_back();
        } else if (event == Json::parse_event_t::key && !open_objects.empty()) {
            const std::string& key = parsed.get_ref<const std::string&>();
            if (!open_objects.back().insert(key).second && duplicate.empty()) duplicate = key;
        }
        return true;
    };
    try {
        Json j = Json::parse(text, on_event);
        if (!duplicate.empty())
            return Unexpected(Failure{"member \"" + duplicate + "\" appears twice in one object"});
        return j;
    } catch (const Json::exception& e) {
        return Unexpected(Failure{"not JSON: " + json_message(e.what())});
    }
}

Outcome<Script> load_script(std::istream& in, const std::string& name) {
    Script script;
    script.name = name;
    std::string text;
    std::size_t line = 0;
    while (std::getline(in, text)) {
        ++line;
        if (!text.empty() && text.back() == '\r') text.pop_back();
        const std::size_t first = text.find_first_not_of(" \t");
        if (first == std::string::npos || text[first] == '#') continue;
        auto json = parse_json_strict(text);
        if (!json) return Unexpected(Failure{json.error().message, line});
        try {
            std::vector<std::string> names;
            script.steps.push_back(compile_step(json.value(), line, names));
        } catch (const ScriptFailure& e) {
            return Unexpected(Failure{e.message, line});
        }
    }
    if (in.bad()) return Unexpected(Failure{"cannot read " + name});
    if (script.steps.empty()) return Unexpected(Failure{name + " has no steps"});
    return script;
}

Outcome<Script> load_script_file(const std::string& path) {
    if (path == "-") return load_script(std::cin, "-");
    std::ifstream in(path);
    if (!in) return Unexpected(Failure{"cannot open script '" + path + "'"});
    return load_script(in, path);
}

}  // namespace strata::cli

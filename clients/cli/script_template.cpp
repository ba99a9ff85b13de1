#include "clients/cli/script_template.h"

#include <charconv>
#include <cmath>

namespace strata::cli {

namespace {

/// A whole number as the JSON integer it stands for, anything else as a double.
Json number_json(double v) {
    if (v == std::floor(v) && std::fabs(v) < 9007199254740992.0) {
        if (v >= 0) return Json(static_cast<uint64_t>(v));
        return Json(static_cast<int64_t>(v));
    }
    return Json(v);
}

}  // namespace

// --- StringTemplate ---------------------------------------------------------------------------

Outcome<StringTemplate> StringTemplate::compile(const std::string& text,
                                                const std::vector<std::string>& names_in_scope) {
    StringTemplate t;
    std::string literal;
    auto flush = [&] {
        if (!literal.empty()) t.m_parts.push_back({std::move(literal), {}, false});
        literal.clear();
    };
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if ((c == '{' || c == '}') && i + 1 < text.size() && text[i + 1] == c) {
            literal += c;  // "{{" or "}}": a literal brace
            ++i;
            continue;
        }
        if (c == '}')
            return Unexpected(Failure{"unmatched '}' in \"" + text + "\" (write }} for a brace)"});
        if (c != '{') {
            literal += c;
            continue;
        }
        const std::size_t close = text.find('}', i + 1);
        if (close == std::string::npos)
            return Unexpected(Failure{"unclosed '{' in \"" + text + "\" (write {{ for a brace)"});
        std::string_view inner = std::string_view(text).substr(i + 1, close - i - 1);
        // "{expr:4}": the value zero-padded to 4 characters (frame numbers that sort).
        std::size_t width = 0;
        if (const std::size_t colon = inner.rfind(':'); colon != std::string_view::npos) {
            const std::string_view digits = inner.substr(colon + 1);
            const auto [end, ec] =
                std::from_chars(digits.data(), digits.data() + digits.size(), width);
            if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() ||
                width > 32)
                return Unexpected(Failure{"bad width '" + std::string(digits) + "' in \"" + text +
                                          "\" (write {expr:4} to zero-pad to 4 characters)"});
            inner = inner.substr(0, colon);
        }
        auto expr = Expression::compile(inner, names_in_scope);
        if (!expr) return Unexpected(Failure{expr.error().message + " in \"" + text + "\""});
        flush();
        t.m_parts.push_back({{}, std::move(expr.value()), true, width});
        i = close;
    }
    flush();
    t.m_whole = t.m_parts.size() == 1 && t.m_parts.front().is_expr && !t.m_parts.front().width;
    return t;
}

Outcome<std::string> StringTemplate::render(const Bindings& vars) const {
    std::string out;
    for (const Part& p : m_parts) {
        if (!p.is_expr) {
            out += p.text;
            continue;
        }
        auto v = p.expr.evaluate(vars);
        if (!v) return Unexpected(v.error());
        std::string number = format_number(v.value());
        if (number.size() < p.width) {
            // Zeros go after a sign: -7 padded to 4 is -007.
            const std::size_t at = number[0] == '-' ? 1 : 0;
            number.insert(at, p.width - number.size(), '0');
        }
        out += number;
    }
    return out;
}

Outcome<Json> StringTemplate::instantiate(const Bindings& vars) const {
    if (m_whole) {
        auto v = m_parts.front().expr.evaluate(vars);
        if (!v) return Unexpected(v.error());
        return number_json(v.value());
    }
    auto s = render(vars);
    if (!s) return Unexpected(s.error());
    return Json(std::move(s.value()));
}

// --- CountTemplate ----------------------------------------------------------------------------

Outcome<CountTemplate> CountTemplate::compile(const Json& v,
                                              const std::vector<std::string>& names) {
    CountTemplate c;
    if (v.is_number()) {
        c.m_expr = Expression::constant(v.get<double>());
    } else if (v.is_string()) {
        auto t = StringTemplate::compile(v.get<std::string>(), names);
        if (!t) return Unexpected(t.error());
        if (!t.value().is_number())
            return Unexpected(Failure{"a repeat count must be a number or one \"{expression}\""});
        c.m_expr = t.value().expression();
    } else {
        return Unexpected(Failure{"a repeat count must be a number or one \"{expression}\", not " +
                                  std::string(v.type_name())});
    }
    if (v.is_number()) {
        // Constant counts are checked when the script loads.
        auto n = c.evaluate(Bindings{});
        if (!n) return Unexpected(n.error());
    }
    return c;
}

Outcome<uint64_t> CountTemplate::evaluate(const Bindings& vars) const {
    auto v = m_expr.evaluate(vars);
    if (!v) return Unexpected(v.error());
    const double d = v.value();
    if (d < 0 || d != std::floor(d) || d > MAX_REPEAT_COUNT)
        return Unexpected(Failure{"a repeat count must be a whole number from 0 to " +
                                  format_number(MAX_REPEAT_COUNT) + ", not " + format_number(d)});
    return static_cast<uint64_t>(d);
}

// --- JsonTemplate -----------------------------------------------------------------------------

struct JsonTemplate::Node {
    enum class Kind : uint8_t { Literal, String, Object, Array, Splice };
    Kind kind = Kind::Literal;
    Json literal;                        ///< Literal: the value as written
    StringTemplate text;                 ///< String
    std::vector<std::string> keys;       ///< Object: member names, parallel to children
    std::vector<Node> children;          ///< Object members, Array elements, Splice items
    std::optional<CountTemplate> count;  ///< Splice
    std::string var;                     ///< Splice: the iteration variable
};

namespace {

using Node = JsonTemplate::Node;

bool is_splice(const Json& v) {
    return v.is_object() && v.contains("repeat");
}

bool all_literal(const std::vector<Node>& nodes) {
    for (const Node& n : nodes)
        if (n.kind != Node::Kind::Literal) return false;
    return true;
}

Node compile_node(const Json& v, std::vector<std::string>& names);
Node compile_splice(const Json& v, std::vector<std::string>& names);

/// The elements of an array (or of a splice's items), any of which may be a splice.
std::vector<Node> compile_elements(const Json& array, std::vector<std::string>& names) {
    std::vector<Node> out;
    out.reserve(array.size());
    for (const Json& e : array)
        out.push_back(is_splice(e) ? compile_splice(e, names) : compile_node(e, names));
    return out;
}

Node compile_splice(const Json& v, std::vector<std::string>& names) {
    if (auto bad = check_members(v, "an inline repeat", {"repeat", "var", "items"}))
        throw ScriptFailure{bad->message};
    Node n;
    n.kind = Node::Kind::Splice;
    n.count = value_or_throw(CountTemplate::compile(v["repeat"], names));
    n.var = "n";
    if (v.contains("var")) {
        if (!v["var"].is_string()) throw ScriptFailure{"\"var\" must be a name"};
        n.var = v["var"].get<std::string>();
        if (!is_variable_name(n.var))
            throw ScriptFailure{"\"var\": '" + n.var + "' is not a usable name"};
    }
    if (!v.contains("items") || !v["items"].is_array())
        throw ScriptFailure{"an inline repeat needs \"items\": an array spliced COUNT times"};
    names.push_back(n.var);
    n.children = compile_elements(v["items"], names);
    names.pop_back();
    return n;
}

Node compile_node(const Json& v, std::vector<std::string>& names) {
    Node n;
    if (v.is_string()) {
        n.text = value_or_throw(StringTemplate::compile(v.get<std::string>(), names));
        if (!n.text.is_literal()) n.kind = Node::Kind::String;
    } else if (v.is_object()) {
        for (const auto& [key, member] : v.items()) {
            n.keys.push_back(key);
            n.children.push_back(compile_node(member, names));
        }
        if (!all_literal(n.children)) n.kind = Node::Kind::Object;
    } else if (v.is_array()) {
        n.children = compile_elements(v, names);
        if (!all_literal(n.children)) n.kind = Node::Kind::Array;
    }
    if (n.kind == Node::Kind::Literal) {
        n.literal = v;
        n.keys.clear();
        n.children.clear();
    }
    return n;
}

void instantiate_into(const Node& n, Bindings& vars, Json& out);

void append_elements(const std::vector<Node>& nodes, Bindings& vars, Json& array) {
    for (const Node& c : nodes) {
        if (c.kind != Node::Kind::Splice) {
            Json item;
            instantiate_into(c, vars, item);
            array.push_back(std::move(item));
            continue;
        }
        const uint64_t count = value_or_throw(c.count->evaluate(vars));
        for (uint64_t i = 0; i < count; ++i) {
            vars.push(c.var, double(i));
            append_elements(c.children, vars, array);
            vars.pop();
        }
    }
}

void instantiate_into(const Node& n, Bindings& vars, Json& out) {
    switch (n.kind) {
        case Node::Kind::Literal:
            out = n.literal;
            return;
        case Node::Kind::String:
            out = value_or_throw(n.text.instantiate(vars));
            return;
        case Node::Kind::Object:
            out = Json::object();
            for (std::size_t i = 0; i < n.keys.size(); ++i)
                instantiate_into(n.children[i], vars, out[n.keys[i]]);
            return;
        case Node::Kind::Array:
            out = Json::array();
            append_elements(n.children, vars, out);
            return;
        case Node::Kind::Splice:
            throw ScriptFailure{"an inline repeat must be an element of an array"};
    }
}

}  // namespace

Outcome<JsonTemplate> JsonTemplate::compile(const Json& v, const std::vector<std::string>& names) {
    try {
        std::vector<std::string> scope = names;
        JsonTemplate t;
        t.m_root = std::make_shared<const Node>(compile_node(v, scope));
        return t;
    } catch (const ScriptFailure& e) {
        return Unexpected(Failure{e.message});
    }
}

Outcome<Json> JsonTemplate::instantiate(Bindings& vars) const {
    try {
        Json out;
        instantiate_into(*m_root, vars, out);
        return out;
    } catch (const ScriptFailure& e) {
        return Unexpected(Failure{e.message});
    }
}

std::optional<Failure> check_members(const Json& obj, const std::string& what,
                                     const std::vector<std::string>& allowed) {
    if (!obj.is_object()) return Failure{what + " must be a JSON object"};
    for (const auto& [key, value] : obj.items()) {
        bool known = false;
        for (const std::string& a : allowed) known = known || a == key;
        if (known) continue;
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
        return Failure{"unknown member \"" + key + "\" in " + what + " (allowed: " + list + ")"};
    }
    return std::nullopt;
}

}  // namespace strata::cli

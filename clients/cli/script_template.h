#pragma once
// JSON with `{...}` substitutions and inline repeats, compiled once and instantiated per step.
//
//   - In any string value, `{expr}` is replaced by the expression's value (script_expr.h), and
//     `{expr:4}` by the value zero-padded to 4 characters; `{{` and `}}` stand for literal
//     braces. A string that is exactly one `{expr}` becomes a
//     JSON number, so `"{n * 0.1}"` can stand where a number is expected. Object keys are never
//     substituted.
//   - In any array, an element `{"repeat": COUNT, "var": "i", "items": [...]}` is replaced by
//     COUNT copies of its items, spliced in place, with `i` (default `n`) bound to 0, 1, ...
//     COUNT may itself be a number or an expression string.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clients/cli/json.h"
#include "clients/cli/outcome.h"
#include "clients/cli/script_expr.h"

namespace strata::cli {

/// Most copies one repeat may produce (a typo such as 1e9 fails instead of eating memory).
constexpr double MAX_REPEAT_COUNT = 10'000'000;

/// A string with substitutions.
class StringTemplate {
public:
    /// Compiles `text`; the names in scope are checked now.
    static Outcome<StringTemplate> compile(const std::string& text,
                                           const std::vector<std::string>& names_in_scope);

    /// True when the text has no substitution.
    bool is_literal() const {
        return m_parts.empty() || (m_parts.size() == 1 && !m_parts.front().is_expr);
    }
    /// True when the text is exactly one `{expr}`: it instantiates to a number.
    bool is_number() const { return m_whole; }
    /// The expression of a whole-number template (is_number() must hold).
    const Expression& expression() const { return m_parts.front().expr; }

    /// The text with every substitution made.
    Outcome<std::string> render(const Bindings& vars) const;
    /// The JSON value: a number for a whole `{expr}`, else a string.
    Outcome<Json> instantiate(const Bindings& vars) const;

private:
    struct Part {
        std::string text;  ///< literal text, when not an expression
        Expression expr;
        bool is_expr = false;
        std::size_t width = 0;  ///< zero-pad the value to this many characters ({n:4})
    };
    std::vector<Part> m_parts;
    bool m_whole = false;
};

/// A repeat count: a number or an expression, checked to be a whole number in range.
class CountTemplate {
public:
    static Outcome<CountTemplate> compile(const Json& v, const std::vector<std::string>& names);
    /// The count under `vars`.
    Outcome<uint64_t> evaluate(const Bindings& vars) const;

private:
    Expression m_expr;
};

/// A JSON value with substitutions and inline repeats.
class JsonTemplate {
public:
    static Outcome<JsonTemplate> compile(const Json& v, const std::vector<std::string>& names);
    /// The JSON value under `vars`.
    Outcome<Json> instantiate(Bindings& vars) const;

    struct Node;

private:
    std::shared_ptr<const Node> m_root;
};

/// Checks that `obj` is an object whose members are all in `allowed`: nullopt, or the failure
/// naming the first unknown member and what `what` allows.
std::optional<Failure> check_members(const Json& obj, const std::string& what,
                                     const std::vector<std::string>& allowed);

}  // namespace strata::cli

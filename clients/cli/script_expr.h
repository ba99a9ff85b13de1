#pragma once
// The arithmetic of `{...}` in scripts: a tiny, safe expression language over doubles.
//
//   expr     := term (('+' | '-') term)*
//   term     := unary (('*' | '/' | '%') unary)*
//   unary    := ('-' | '+') unary | power
//   power    := primary ('^' unary)?              right-associative: 2^3^2 = 2^9; -2^2 = -4
//   primary  := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'
//
// Names are the iteration variables of the enclosing repeats (`n` unless a repeat names its own
// with "var") and the constants `pi` and `e`. Functions: sin cos tan asin acos atan atan2 sqrt
// abs floor ceil round min max pow exp log clamp(x, lo, hi). `%` is a floored modulo: the result
// has the sign of the divisor, so `(n - 1) % 10` is 9 at n = 0. Division or modulo by zero and a
// result that is not finite are errors, never NaN in a request.

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "clients/cli/outcome.h"

namespace strata::cli {

/// Variable bindings while a script plays: the iteration variables of the repeats the current
/// step is inside, innermost last (an inner repeat's variable hides an outer one of that name).
class Bindings {
public:
    void push(std::string name, double value) { m_vars.emplace_back(std::move(name), value); }
    void pop() { m_vars.pop_back(); }
    /// The innermost binding of `name`, or nullptr.
    const double* find(std::string_view name) const;
    /// "n=3, i=7": every binding, outermost first ("" when none).
    std::string describe() const;
    bool empty() const { return m_vars.empty(); }

private:
    std::vector<std::pair<std::string, double>> m_vars;
};

/// A compiled expression.
class Expression {
public:
    /// Compiles `text`; `names_in_scope` are the variables it may use (checked now, so a typo is
    /// reported when the script loads, not halfway through it).
    static Outcome<Expression> compile(std::string_view text,
                                       const std::vector<std::string>& names_in_scope);
    /// A constant.
    static Expression constant(double value);

    /// The value under `vars`; fails on division by zero or a result that is not finite.
    Outcome<double> evaluate(const Bindings& vars) const;
    /// The source text ("" for a constant).
    const std::string& text() const { return m_text; }

    struct Node;

private:
    std::shared_ptr<const Node> m_root;  ///< immutable, so copies share it
    std::string m_text;
};

/// True for a name a repeat may bind: a letter or '_' then letters, digits or '_', and not a
/// constant or function name.
bool is_variable_name(std::string_view name);

/// A number as text: integers without a decimal point, others in the shortest form that reads
/// back to the same double.
std::string format_number(double v);

}  // namespace strata::cli

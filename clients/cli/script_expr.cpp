#include "clients/cli/script_expr.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <numbers>

namespace strata::cli {

namespace {

enum class Op : uint8_t { Number, Var, Neg, Add, Sub, Mul, Div, Mod, Pow, Call };

/// A built-in function: name, arity, implementation.
struct Function {
    std::string_view name;
    int arity;
    double (*fn)(const double* args);
};

constexpr Function FUNCTIONS[] = {
    {"sin", 1, [](const double* a) { return std::sin(a[0]); }},
    {"cos", 1, [](const double* a) { return std::cos(a[0]); }},
    {"tan", 1, [](const double* a) { return std::tan(a[0]); }},
    {"asin", 1, [](const double* a) { return std::asin(a[0]); }},
    {"acos", 1, [](const double* a) { return std::acos(a[0]); }},
    {"atan", 1, [](const double* a) { return std::atan(a[0]); }},
    {"atan2", 2, [](const double* a) { return std::atan2(a[0], a[1]); }},
    {"sqrt", 1, [](const double* a) { return std::sqrt(a[0]); }},
    {"abs", 1, [](const double* a) { return std::fabs(a[0]); }},
    {"floor", 1, [](const double* a) { return std::floor(a[0]); }},
    {"ceil", 1, [](const double* a) { return std::ceil(a[0]); }},
    {"round", 1, [](const double* a) { return std::round(a[0]); }},
    {"min", 2, [](const double* a) { return std::fmin(a[0], a[1]); }},
    {"max", 2, [](const double* a) { return std::fmax(a[0], a[1]); }},
    {"pow", 2, [](const double* a) { return std::pow(a[0], a[1]); }},
    {"exp", 1, [](const double* a) { return std::exp(a[0]); }},
    {"log", 1, [](const double* a) { return std::log(a[0]); }},
    {"clamp", 3, [](const double* a) { return std::fmin(std::fmax(a[0], a[1]), a[2]); }},
};

constexpr std::size_t MAX_DEPTH = 64;
constexpr std::size_t MAX_ARGS = 3;

struct ParseError {
    std::string message;
};

}  // namespace

struct Expression::Node {
    Op op = Op::Number;
    double number = 0.0;
    std::string name;                    ///< Var
    const Function* function = nullptr;  ///< Call
    std::vector<std::unique_ptr<Node>> args;
};

namespace {

using Node = Expression::Node;
using NodePtr = std::unique_ptr<Node>;

NodePtr make(Op op, std::vector<NodePtr> args) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->args = std::move(args);
    return n;
}

class Parser {
public:
    Parser(std::string_view text, const std::vector<std::string>& names)
        : m_text(text), m_names(names) {}

    NodePtr parse() {
        NodePtr root = expr();
        skip_space();
        if (m_pos != m_text.size()) fail("unexpected '" + std::string(1, m_text[m_pos]) + "'");
        return root;
    }

private:
    [[noreturn]] void fail(const std::string& why) const {
        throw ParseError{why + " at column " + std::to_string(m_pos + 1)};
    }
    void skip_space() {
        while (m_pos < m_text.size() && (m_text[m_pos] == ' ' || m_text[m_pos] == '\t')) ++m_pos;
    }
    bool accept(char c) {
        skip_space();
        if (m_pos < m_text.size() && m_text[m_pos] == c) {
            ++m_pos;
            return true;
        }
        return false;
    }
    void expect(char c) {
        if (!accept(c)) {
            if (m_pos >= m_text.size())
                fail(std::string("expected '") + c + "' but the text ended");
            fail(std::string("expected '") + c + "'");
        }
    }
    /// Guards the recursion so that "((((..." cannot overflow the stack.
    struct Depth {
        explicit Depth(Parser& p) : m_p(p) {
            if (++m_p.m_depth > MAX_DEPTH) m_p.fail("expression nested too deeply");
        }
        ~Depth() { --m_p.m_depth; }
        Parser& m_p;
    };

    NodePtr expr() {
        Depth guard(*this);
        NodePtr left = term();
        for (;;) {
            const Op op = accept('+') ? Op::Add : accept('-') ? Op::Sub : Op::Number;
            if (op == Op::Number) return left;
            std::vector<NodePtr> args;
            args.push_back(std::move(left));
            args.push_back(term());
            left = make(op, std::move(args));
        }
    }
    NodePtr term() {
        NodePtr left = unary();
        for (;;) {
            const Op op = accept('*')   ? Op::Mul
                          : accept('/') ? Op::Div
                          : accept('%') ? Op::Mod
                                        : Op::Number;
            if (op == Op::Number) return left;
            std::vector<NodePtr> args;
            args.push_back(std::move(left));
            args.push_back(unary());
            left = make(op, std::move(args));
        }
    }
    NodePtr unary() {
        Depth guard(*this);
        if (accept('-')) {
            std::vector<NodePtr> args;
            args.push_back(unary());
            return make(Op::Neg, std::move(args));
        }
        if (accept('+')) return unary();
        NodePtr base = primary();
        if (!accept('^')) return base;
        std::vector<NodePtr> args;
        args.push_back(std::move(base));
        args.push_back(unary());
        return make(Op::Pow, std::move(args));
    }
    NodePtr primary() {
        skip_space();
        if (m_pos >= m_text.size()) fail("expected a number, a name or '(' but the text ended");
        const char c = m_text[m_pos];
        if (c == '(') {
            ++m_pos;
            NodePtr inner = expr();
            expect(')');
            return inner;
        }
        if ((c >= '0' && c <= '9') || c == '.') return number();
        if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
        fail("unexpected '" + std::string(1, c) + "'");
    }
    NodePtr number() {
        double v = 0.0;
        const char* begin = m_text.data() + m_pos;
        const auto [end, ec] = std::from_chars(begin, m_text.data() + m_text.size(), v);
        if (ec != std::errc()) fail("malformed number");
        m_pos += std::size_t(end - begin);
        auto n = std::make_unique<Node>();
        n->number = v;
        return n;
    }
    NodePtr name() {
        const std::size_t start = m_pos;
        while (m_pos < m_text.size() &&
               (std::isalnum(static_cast<unsigned char>(m_text[m_pos])) || m_text[m_pos] == '_'))
            ++m_pos;
        const std::string id(m_text.substr(start, m_pos - start));
        if (accept('(')) return call(id, start);
        auto n = std::make_unique<Node>();
        if (id == "pi" || id == "e") {
            n->number = id == "pi" ? std::numbers::pi : std::numbers::e;
            return n;
        }
        bool known = false;
        for (const std::string& s : m_names) known = known || s == id;
        if (!known) {
            m_pos = start;
            fail("unknown name '" + id + "'" +
                 (m_names.empty() ? std::string(" (no repeat encloses this step)")
                                  : " (in scope: " + join_names() + ", pi, e)"));
        }
        n->op = Op::Var;
        n->name = id;
        return n;
    }
    NodePtr call(const std::string& id, std::size_t start) {
        const Function* f = nullptr;
        for (const Function& candidate : FUNCTIONS) f = candidate.name == id ? &candidate : f;
        if (!f) {
            m_pos = start;
            fail("unknown function '" + id + "'");
        }
        std::vector<NodePtr> args;
        if (!accept(')')) {
            do {
                args.push_back(expr());
            } while (accept(','));
            expect(')');
        }
        if (int(args.size()) != f->arity) {
            m_pos = start;
            fail(id + "() takes " + std::to_string(f->arity) + " argument" +
                 (f->arity == 1 ? "" : "s") + ", not " + std::to_string(args.size()));
        }
        NodePtr n = make(Op::Call, std::move(args));
        n->function = f;
        return n;
    }
    std::string join_names() const {
        std::string out;
        for (const std::string& s : m_names)
            if (out.find(s) == std::string::npos) out += (out.empty() ? "" : ", ") + s;
        return out;
    }

    std::string_view m_text;
    const std::vector<std::string>& m_names;
    std::size_t m_pos = 0;
    std::size_t m_depth = 0;
};

struct EvalError {
    std::string message;
};

double eval(const Node& n, const Bindings& vars) {
    auto arg = [&](std::size_t i) { return eval(*n.args[i], vars); };
    switch (n.op) {
        case Op::Number:
            return n.number;
        case Op::Var: {
            const double* v = vars.find(n.name);
            if (!v) throw EvalError{"'" + n.name + "' is not bound here"};
            return *v;
        }
        case Op::Neg:
            return -arg(0);
        case Op::Add:
            return arg(0) + arg(1);
        case Op::Sub:
            return arg(0) - arg(1);
        case Op::Mul:
            return arg(0) * arg(1);
        case Op::Div: {
            const double a = arg(0), b = arg(1);
            if (b == 0.0) throw EvalError{"division by zero"};
            return a / b;
        }
        case Op::Mod: {
            const double a = arg(0), b = arg(1);
            if (b == 0.0) throw EvalError{"modulo by zero"};
            const double r = std::fmod(a, b);
            return (r != 0.0 && ((r < 0.0) != (b < 0.0))) ? r + b : r;
        }
        case Op::Pow:
            return std::pow(arg(0), arg(1));
        case Op::Call: {
            double a[MAX_ARGS] = {};
            for (std::size_t i = 0; i < n.args.size(); ++i) a[i] = arg(i);
            return n.function->fn(a);
        }
    }
    return 0.0;
}

}  // namespace

const double* Bindings::find(std::string_view name) const {
    for (auto it = m_vars.rbegin(); it != m_vars.rend(); ++it)
        if (it->first == name) return &it->second;
    return nullptr;
}

std::string Bindings::describe() const {
    std::string out;
    for (const auto& [name, value] : m_vars)
        out += (out.empty() ? "" : ", ") + name + "=" + format_number(value);
    return out;
}

Outcome<Expression> Expression::compile(std::string_view text,
                                        const std::vector<std::string>& names_in_scope) {
    try {
        Expression e;
        e.m_root = Parser(text, names_in_scope).parse();
        e.m_text = std::string(text);
        return e;
    } catch (const ParseError& err) {
        return Unexpected(Failure{"bad expression '" + std::string(text) + "': " + err.message});
    }
}

Expression Expression::constant(double value) {
    auto n = std::make_shared<Node>();
    n->number = value;
    Expression e;
    e.m_root = std::move(n);
    return e;
}

Outcome<double> Expression::evaluate(const Bindings& vars) const {
    try {
        const double v = eval(*m_root, vars);
        if (!std::isfinite(v))
            return Unexpected(
                Failure{"expression '" + m_text + "' is not finite (" +
                        (vars.empty() ? std::string("no bindings") : vars.describe()) + ")"});
        return v;
    } catch (const EvalError& err) {
        return Unexpected(Failure{"expression '" + m_text + "': " + err.message + " (" +
                                  (vars.empty() ? std::string("no bindings") : vars.describe()) +
                                  ")"});
    }
}

bool is_variable_name(std::string_view name) {
    if (name.empty() || name == "pi" || name == "e") return false;
    if (!std::isalpha(static_cast<unsigned char>(name[0])) && name[0] != '_') return false;
    for (const char c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
    for (const Function& f : FUNCTIONS)
        if (f.name == name) return false;
    return true;
}

std::string format_number(double v) {
    if (v == std::floor(v) && std::fabs(v) < 9007199254740992.0) {
        char buf[32];
        const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, static_cast<long long>(v));
        return std::string(buf, end);
    }
    char buf[64];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, end);
}

}  // namespace strata::cli

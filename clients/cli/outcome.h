#pragma once
// Errors as values inside the command-line client: a value or a Failure that says what went
// wrong and, for scripts, on which line.

#include <cstddef>
#include <string>
#include <utility>
#include <variant>

namespace strata::cli {

/// What went wrong. `line` is the 1-based script line the failure belongs to (0: none).
struct Failure {
    std::string message;
    std::size_t line = 0;

    /// "line 7: message", or the message alone without a line.
    std::string describe() const {
        return line ? "line " + std::to_string(line) + ": " + message : message;
    }
};

/// Either a value or a Failure.
template <class T>
class Outcome {
public:
    Outcome(T value) : m_v(std::move(value)) {}        // NOLINT: implicit by design
    Outcome(Failure error) : m_v(std::move(error)) {}  // NOLINT: implicit by design

    bool ok() const { return m_v.index() == 0; }
    explicit operator bool() const { return ok(); }
    T& value() & { return std::get<0>(m_v); }
    const T& value() const& { return std::get<0>(m_v); }
    T&& value() && { return std::get<0>(std::move(m_v)); }
    const Failure& error() const { return std::get<1>(m_v); }

private:
    std::variant<T, Failure> m_v;
};

/// Thrown inside the recursive readers of scripts only (templates, steps), so that nested code
/// stays short; every public function catches it and returns the Failure as a value.
struct ScriptFailure {
    std::string message;
};

/// The value of `o`, or a thrown ScriptFailure with its message.
template <class T>
T value_or_throw(Outcome<T>&& o) {
    if (!o) throw ScriptFailure{o.error().message};
    return std::move(o).value();
}

}  // namespace strata::cli

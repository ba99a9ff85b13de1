#pragma once
// Errors as values inside the command-line client: a value or a Failure that says what went
// wrong and, for scripts, on which line.

#include <cstddef>
#include <string>
#include <utility>

#include "engine/core/expected.h"

namespace strata::cli {

using strata::Expected;
using strata::Unexpected;

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
using Outcome = Expected<T, Failure>;

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

#pragma once
// Why a request could not be turned into engine structs. The parser stages map onto HTTP status
// classes in the server (Syntax/Schema/TooDeep: 400, Value: 422, TooLarge: 413), but this header
// knows nothing of HTTP.

#include <cstddef>
#include <exception>
#include <string>
#include <utility>

#include "engine/core/result.h"

namespace strata::protocol {

enum class RequestErrorKind : uint8_t {
    Syntax,    ///< the body is not JSON (or has a duplicate key)
    TooDeep,   ///< JSON nesting deeper than the configured limit
    TooLarge,  ///< an array or the whole request exceeds a configured limit
    Schema,    ///< JSON that does not match the protocol schema: type, missing or unknown field
    Value,     ///< matches the schema but a value cannot be used (not finite, bad length, ...)
};

/// One request error with the place it refers to.
struct RequestError {
    RequestErrorKind kind = RequestErrorKind::Schema;
    ErrorCode code = ErrorCode::InvalidArgument;  ///< the engine's vocabulary, for Value errors
    std::string message;
    std::string pointer;  ///< JSON pointer into the request body; "" is the whole body
    std::size_t edit_index = Error::NO_INDEX;
};

/// Either a parsed value or a RequestError.
template <class T>
using Parsed = Expected<T, RequestError>;

/// Thrown inside the parsers only, so that deeply nested readers stay short; every public parse
/// function catches it and returns the RequestError as a value.
class RequestFailure : public std::exception {
public:
    explicit RequestFailure(RequestError e) : m_error(std::move(e)) {}
    const char* what() const noexcept override { return m_error.message.c_str(); }
    const RequestError& error() const { return m_error; }

private:
    RequestError m_error;
};

/// Escapes one JSON pointer reference token ('~' -> "~0", '/' -> "~1").
std::string escape_pointer_token(std::string_view token);

}  // namespace strata::protocol

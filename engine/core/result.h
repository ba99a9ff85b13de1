#pragma once
// Errors as values at the engine boundary: anything a caller can cause comes back as an Error.

#include <cstddef>
#include <string>
#include <utility>
#include <variant>

namespace strata {

/// What went wrong, in a form the protocol layer can map to a status code.
enum class ErrorCode {
    InvalidArgument,    ///< a value is malformed or outside its allowed range
    NotFinite,          ///< a number is NaN or infinite
    UnknownId,          ///< an edit names an object that does not exist
    DuplicateId,        ///< an edit creates an object whose id is taken
    OutOfRange,         ///< an index or vertex range is outside the mesh
    DegenerateTransform,///< a transform is singular or badly conditioned
    InUse,              ///< the object is still referenced (a mesh with instances)
    EmptyMesh,          ///< a mesh without vertices or triangles
    StaleHandle,        ///< a handle whose object was removed
    TooLarge,           ///< a request exceeds a configured limit
    VersionMismatch,    ///< a conditional apply found the scene at another version
    Internal,           ///< a failure inside Embree or the engine itself
};

/// Stable lower-case name of an error code, used in reports and problem documents.
const char* error_code_name(ErrorCode code);

/// One error. For batch validation, `edit_index` is the position of the offending edit and
/// `field` a '/'-separated path inside that edit (for example "positions/12").
struct Error {
    static constexpr std::size_t NO_INDEX = static_cast<std::size_t>(-1);

    ErrorCode code = ErrorCode::Internal;
    std::string message;
    std::size_t edit_index = NO_INDEX;
    std::string field;

    /// "edit 3 (positions/12): position is NaN" style one-line description.
    std::string describe() const;
};

/// Either a value or an Error.
template <class T>
class Result {
public:
    Result(T value) : m_v(std::move(value)) {}           // NOLINT: implicit by design
    Result(Error error) : m_v(std::move(error)) {}       // NOLINT: implicit by design

    bool ok() const { return m_v.index() == 0; }
    explicit operator bool() const { return ok(); }
    T& value() & { return std::get<0>(m_v); }
    const T& value() const& { return std::get<0>(m_v); }
    T&& value() && { return std::get<0>(std::move(m_v)); }
    const Error& error() const { return std::get<1>(m_v); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

private:
    std::variant<T, Error> m_v;
};

/// Success or an Error.
class Status {
public:
    Status() = default;
    Status(Error error) : m_error(std::move(error)), m_ok(false) {}  // NOLINT: implicit by design
    static Status success() { return {}; }

    bool ok() const { return m_ok; }
    explicit operator bool() const { return m_ok; }
    const Error& error() const { return m_error; }

private:
    Error m_error;
    bool m_ok = true;
};

/// Builds an Error; `field` is optional.
inline Error make_error(ErrorCode code, std::string message, std::string field = {}) {
    Error e;
    e.code = code;
    e.message = std::move(message);
    e.field = std::move(field);
    return e;
}

}  // namespace strata

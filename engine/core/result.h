#pragma once
// Errors as values at the engine boundary: anything a caller can cause comes back as an Error.

#include <cstddef>
#include <string>
#include <utility>

#include "engine/core/expected.h"

namespace strata {

/// What went wrong, in a form the protocol layer can map to a status code.
enum class ErrorCode {
    InvalidArgument,      ///< a value is malformed or outside its allowed range
    NotFinite,            ///< a number is NaN or infinite
    UnknownId,            ///< an edit names an object that does not exist
    DuplicateId,          ///< an edit creates an object whose id is taken
    OutOfRange,           ///< an index or vertex range is outside the mesh
    DegenerateTransform,  ///< a transform is singular or badly conditioned
    InUse,                ///< the object is still referenced (a mesh with instances)
    Cycle,                ///< a group would end up inside itself
    EmptyMesh,            ///< a mesh without vertices or triangles
    StaleHandle,          ///< a handle whose object was removed
    TooLarge,             ///< a request exceeds a configured limit
    VersionMismatch,      ///< a conditional apply found the scene at another version
    NothingToUndo,        ///< undo or redo with an empty stack (edit_history.h)
    Cancelled,            ///< a launch stopped early (CancelToken: deadline, client gone, shutdown)
    Storage,              ///< the data directory could not be written or read (journal, snapshot)
    Internal,             ///< a failure inside Embree or the engine itself
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
using Result = Expected<T, Error>;

/// Success or an Error.
using Status = Expected<void, Error>;

/// Builds an Error; `field` is optional.
inline Error make_error(ErrorCode code, std::string message, std::string field = {}) {
    Error e;
    e.code = code;
    e.message = std::move(message);
    e.field = std::move(field);
    return e;
}

/// An Error as the failure of a Result or Status: `return failure(ErrorCode::UnknownId, ...)`.
inline Unexpected<Error> failure(ErrorCode code, std::string message, std::string field = {}) {
    return Unexpected(make_error(code, std::move(message), std::move(field)));
}

}  // namespace strata

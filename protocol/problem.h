#pragma once
// Problem details (RFC 9457): the one vocabulary of errors at the protocol boundary. The parsers
// (Parsed<T>) and the importers (assets::Imported<T>) answer with a Problem, the API with its
// document; engine Errors become Problems here, once. A Problem carries its HTTP status as the
// `status` member the RFC defines; nothing here depends on an HTTP library. The types and
// constructors (problem_types.cpp) need nothing beyond the engine's result types; the
// conversions and the JSON document (problem.cpp) are the protocol's.

#include <cstddef>
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "engine/core/result.h"

namespace strata::protocol {

using Json = nlohmann::json;
struct EditSource;

/// Every problem type Strata answers with; each has a stable URI, a title and a status.
enum class ProblemType : uint8_t {
    MalformedJson,        ///< 400 the body is not JSON
    InvalidRequest,       ///< 400 the body does not match the schema (or a query is malformed)
    NestingTooDeep,       ///< 400 JSON nesting beyond the limit
    TooLarge,             ///< 413 body, array, mesh or frame beyond a limit
    InvalidValue,         ///< 422 a value is outside its allowed range
    NotFinite,            ///< 422 a number is NaN, infinite or overflows a float
    UnknownId,            ///< 422 an edit names an object that does not exist
    DuplicateId,          ///< 422 an edit creates an object whose id is taken
    OutOfRange,           ///< 422 an index or vertex range is outside the mesh
    DegenerateTransform,  ///< 422 a singular or badly conditioned transform
    InUse,                ///< 422 the object is still referenced
    Cycle,                ///< 422 a group would end up inside itself
    EmptyMesh,            ///< 422 a mesh without vertices or triangles
    InvalidAsset,         ///< 422 an uploaded model file is malformed or uses what Strata lacks
    VersionMismatch,      ///< 412 If-Match names another version
    NothingToUndo,        ///< 409 undo or redo with nothing left to take back or redo
    SceneConflict,        ///< 409 a named scene cannot be deleted or made again just now
    NotFound,             ///< 404 no such route or object
    MethodNotAllowed,     ///< 405 the route exists for other methods
    Unauthorized,         ///< 401 missing or wrong bearer token
    Forbidden,            ///< 403 the token's role in the scene does not allow the request
    Unavailable,          ///< 503 the server is shutting down
    DeadlineExceeded,     ///< 503 a render ran past --render-timeout and was stopped
    RequestTimeout,       ///< 408 the request did not arrive in time (headers or body)
    UriTooLong,           ///< 414 the request target is longer than the limit
    UnsupportedEncoding,  ///< 415 a Content-Encoding the server does not decode
    UnsupportedMedia,     ///< 415 a body type the endpoint does not read (multipart, ...)
    ExpectationFailed,    ///< 417 an Expect other than 100-continue
    TooManyConnections,   ///< 429 this client already holds its share of connections
    HeadersTooLarge,      ///< 431 too many header fields, or too many bytes of them
    NotImplemented,       ///< 501 an HTTP method the server does not know
    HttpVersion,          ///< 505 an HTTP version other than 1.0 and 1.1
    Internal,             ///< 500 a bug or an Embree failure
};

/// One problem document.
struct Problem {
    ProblemType type = ProblemType::Internal;
    int status = 500;
    std::string detail;
    std::size_t edit_index = Error::NO_INDEX;
    std::optional<std::string> pointer;  ///< JSON pointer into the request, when one applies
    std::optional<std::string> file;     ///< POST /v1/assets: the uploaded file's name
    std::optional<std::string> element;  ///< POST /v1/assets: the element of the file at fault
};

/// "https://strata.dev/problems/<slug>".
std::string problem_type_uri(ProblemType t);
/// Short human-readable summary of the type ("Unknown id").
const char* problem_title(ProblemType t);
/// The HTTP status that goes with the type.
int problem_status(ProblemType t);
/// What gets this type as an answer (Markdown), for the docs and the OpenAPI description.
const char* problem_when(ProblemType t);

/// A problem of `type` with its default status.
Problem make_problem(ProblemType type, std::string detail);
/// A problem about one place of the request: `pointer` (JSON pointer into the body; "" is the
/// whole body), and a detail that names it first ("/edits/3/positions: expected an array").
Problem problem_at(ProblemType type, std::string pointer, const std::string& what,
                   std::size_t edit_index = Error::NO_INDEX);
/// The problem type of an engine error code (unknown-id for UnknownId, ...).
ProblemType problem_type_of(ErrorCode code);
/// An engine error for an edit batch: `edit_index` and `field` become `/edits/<i>/<field>`,
/// renamed to the wire member the edit used (positions_b64, shape, ...).
Problem problem_from_batch_error(const Error& e, const std::vector<EditSource>& sources);
/// An engine error for a request whose fields sit at the root of the body (render).
Problem problem_from(const Error& e);

/// The problem as an application/problem+json document.
Json problem_to_json(const Problem& p);

/// Either a parsed value or the problem with the request.
template <class T>
using Parsed = Expected<T, Problem>;

/// Thrown inside the parsers only, so that deeply nested readers stay short; every public parse
/// function catches it and returns the Problem as a value.
class RequestFailure : public std::exception {
public:
    explicit RequestFailure(Problem p) : m_problem(std::move(p)) {}
    const char* what() const noexcept override { return m_problem.detail.c_str(); }
    const Problem& problem() const { return m_problem; }

private:
    Problem m_problem;
};

/// Escapes one JSON pointer reference token ('~' -> "~0", '/' -> "~1").
std::string escape_pointer_token(std::string_view token);

}  // namespace strata::protocol

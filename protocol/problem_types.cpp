#include "protocol/problem.h"

// The problem types and the Problem's constructors: no dependency beyond the engine's result
// types, so that the importers (strata_assets) answer with Problems too.

namespace strata::protocol {

namespace {

struct TypeInfo {
    const char* slug;
    const char* title;
    int status;
    const char* when;  ///< Markdown: what gets this answer (the README table and the OpenAPI)
};

constexpr TypeInfo TYPES[] = {
    {"malformed-json", "Malformed JSON", 400, "the body is not JSON, or repeats a key"},
    {"invalid-request", "Invalid request", 400,
     "the body does not match the schema: wrong type, missing or unknown member, unknown "
     "op or enum value, out-of-schema range; a malformed query (a bad percent-escape, "
     "invalid UTF-8, a control character, a repeated parameter) or `If-Match`; a "
     "malformed HTTP request (see \"HTTP\" in protocol/README.md)"},
    {"nesting-too-deep", "JSON nested too deeply", 400,
     "JSON nested deeper than `--max-json-depth`"},
    {"too-large", "Content too large", 413,
     "body over `--max-body-mb`, an array over `--max-array-elements`, a JSON document "
     "over `--max-json-values`, a batch (or snapshot) over `--max-batch-edits`, a render "
     "over `--max-pixels`, a mesh over 2^28 vertices or triangles, a batch whose shapes "
     "would generate over 2^24 triangles, a batch that would take the scene over "
     "`--max-scene-triangles` or `--max-scene-vertices` (the pointer names the edit "
     "after which it stays over), an `add_texture` image over 16384 texels a side or "
     "over what `--max-texture-mb` leaves (pointer `/edits/i/data`)"},
    {"invalid-value", "Invalid value", 422,
     "any other value outside its range (a colour above 1, a camera whose `up` is "
     "parallel to the view or whose `eye` or `target` lies beyond 1e15, a flat array "
     "whose length is not a multiple of 3, a base64 array whose size is not a multiple "
     "of 12 bytes, a 4x4 transform whose last row is not `0 0 0 1`, a quaternion whose "
     "length is outside [1e-6, 1e6], a duplicate AOV, an unavailable image format)"},
    {"not-finite", "Number not finite", 422,
     "a number is NaN, infinite or overflows a 32-bit float"},
    {"unknown-id", "Unknown id", 422, "an edit names an object that does not exist"},
    {"duplicate-id", "Duplicate id", 422, "an edit creates an object whose id is taken"},
    {"out-of-range", "Index out of range", 422,
     "a triangle index or a vertex range outside the mesh"},
    {"degenerate-transform", "Degenerate transform", 422,
     "a singular or badly conditioned transform"},
    {"in-use", "Object in use", 422,
     "`remove_mesh` of a mesh that instances still use; `remove_group` of a group with "
     "children, without `\"recursive\": true`"},
    {"cycle", "Group cycle", 422,
     "`update_group` that would put a group inside itself; the message names the cycle "
     "(`'car' > 'wheels' > 'car'`)"},
    {"empty-mesh", "Empty mesh", 422, "a mesh without vertices or triangles"},
    {"invalid-asset", "Invalid asset", 422,
     "`POST /v1/assets`: the file is malformed or uses what Strata does not import (its "
     "`file` and `element` members say where)"},
    {"version-mismatch", "Scene version mismatch", 412, "`If-Match` names another version"},
    {"nothing-to-undo", "Nothing to undo", 409,
     "`POST /v1/undo` with no batch left to take back (none since the start, the newest "
     "snapshot or the history's limits), or `POST /v1/redo` with nothing undone since the last "
     "edit"},
    {"scene-conflict", "Scene conflict", 409,
     "`DELETE /v1/scenes/default` (the default scene is never deleted: send `clear`), or "
     "`PUT /v1/scenes/{scene}` of a scene that exists with another budget, or while an "
     "earlier scene of that name is still being deleted or replaced"},
    {"not-found", "Not found", 404,
     "unknown route, an unknown id in the URL of `GET /v1/scene/...`, a scene that does not "
     "exist (or, with `--tokens-file`, that the token has no role in), or an `at_version` the "
     "server does not hold"},
    {"method-not-allowed", "Method not allowed", 405,
     "the path exists for other methods (see the `Allow` header); `HEAD /v1/render`, "
     "which would have to render to know its headers"},
    {"unauthorized", "Unauthorized", 401, "missing or wrong bearer token"},
    {"forbidden", "Forbidden", 403,
     "with `--tokens-file`: the token's role in the scene does not allow the request (a "
     "read-only token sending edits, `PUT` or `DELETE /v1/scenes/{scene}` without admin)"},
    {"unavailable", "Service unavailable", 503,
     "shutting down (every endpoint but `/livez`; a render still running when "
     "`--shutdown-grace` ends is stopped), or more unfinished request data buffered than "
     "`--max-buffered-mb`"},
    {"deadline-exceeded", "Deadline exceeded", 503,
     "a render ran longer than `--render-timeout` and was stopped"},
    {"request-timeout", "Request timeout", 408,
     "the request's headers did not arrive within `--header-timeout`, or all of it "
     "within `--read-timeout`"},
    {"uri-too-long", "URI too long", 414, "a request target over `--max-uri-bytes`"},
    {"unsupported-encoding", "Unsupported content encoding", 415,
     "a `Content-Encoding` other than `identity`: bodies are never inflated"},
    {"unsupported-media-type", "Unsupported media type", 415,
     "`POST /v1/edits`, `/v1/render` or `/v1/pick` with a `Content-Type` that cannot "
     "carry JSON (`multipart/form-data`, an image, ...); no `Content-Type`, "
     "`application/json`, any `+json` type, `text/plain` and "
     "`application/x-www-form-urlencoded` (curl's `-d`) are read as JSON"},
    {"expectation-failed", "Expectation failed", 417, "an `Expect` other than `100-continue`"},
    {"too-many-connections", "Too many connections", 429,
     "the client already holds `--max-connections-per-client` connections (or the server "
     "`--max-connections`): on this one only `/livez` and `/readyz` are answered"},
    {"headers-too-large", "Request header fields too large", 431,
     "more than `--max-headers` header fields, a head over `--max-header-bytes`, or one "
     "line over 8 KiB"},
    {"not-implemented", "Not implemented", 501,
     "a method other than GET, HEAD, POST, PUT, PATCH, DELETE and OPTIONS"},
    {"http-version-not-supported", "HTTP version not supported", 505,
     "an HTTP version other than 1.0 and 1.1"},
    {"internal", "Internal server error", 500,
     "a bug or an Embree failure (the request is logged)"},
};
static_assert(std::size(TYPES) == std::size_t(ProblemType::Internal) + 1);

}  // namespace

std::string problem_type_uri(ProblemType t) {
    return std::string("https://strata.dev/problems/") + TYPES[int(t)].slug;
}
const char* problem_title(ProblemType t) {
    return TYPES[int(t)].title;
}
int problem_status(ProblemType t) {
    return TYPES[int(t)].status;
}
const char* problem_when(ProblemType t) {
    return TYPES[int(t)].when;
}

Problem make_problem(ProblemType type, std::string detail) {
    Problem p;
    p.type = type;
    p.status = problem_status(type);
    p.detail = std::move(detail);
    return p;
}

Problem problem_at(ProblemType type, std::string pointer, const std::string& what,
                   std::size_t edit_index) {
    Problem p = make_problem(type, pointer.empty() ? what : pointer + ": " + what);
    p.pointer = std::move(pointer);
    p.edit_index = edit_index;
    return p;
}

ProblemType problem_type_of(ErrorCode code) {
    switch (code) {
        case ErrorCode::InvalidArgument:
            return ProblemType::InvalidValue;
        case ErrorCode::NotFinite:
            return ProblemType::NotFinite;
        case ErrorCode::UnknownId:
            return ProblemType::UnknownId;
        case ErrorCode::DuplicateId:
            return ProblemType::DuplicateId;
        case ErrorCode::OutOfRange:
            return ProblemType::OutOfRange;
        case ErrorCode::DegenerateTransform:
            return ProblemType::DegenerateTransform;
        case ErrorCode::InUse:
            return ProblemType::InUse;
        case ErrorCode::Cycle:
            return ProblemType::Cycle;
        case ErrorCode::EmptyMesh:
            return ProblemType::EmptyMesh;
        case ErrorCode::TooLarge:
            return ProblemType::TooLarge;
        case ErrorCode::VersionMismatch:
            return ProblemType::VersionMismatch;
        case ErrorCode::NothingToUndo:
            return ProblemType::NothingToUndo;
        case ErrorCode::Cancelled:
        case ErrorCode::Storage:  // the journal could not take the batch: nothing was applied
            return ProblemType::Unavailable;
        case ErrorCode::StaleHandle:
        case ErrorCode::Internal:
            return ProblemType::Internal;
    }
    return ProblemType::Internal;
}

std::string escape_pointer_token(std::string_view token) {
    std::string out;
    out.reserve(token.size());
    for (char c : token) {
        if (c == '~') {
            out += "~0";
        } else if (c == '/') {
            out += "~1";
        } else {
            out += c;
        }
    }
    return out;
}

}  // namespace strata::protocol

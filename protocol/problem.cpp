#include "protocol/problem.h"

namespace strata::protocol {

namespace {

struct TypeInfo {
    const char* slug;
    const char* title;
    int status;
};

constexpr TypeInfo TYPES[] = {
    {"malformed-json", "Malformed JSON", 400},
    {"invalid-request", "Invalid request", 400},
    {"nesting-too-deep", "JSON nested too deeply", 400},
    {"too-large", "Content too large", 413},
    {"invalid-value", "Invalid value", 422},
    {"not-finite", "Number not finite", 422},
    {"unknown-id", "Unknown id", 422},
    {"duplicate-id", "Duplicate id", 422},
    {"out-of-range", "Index out of range", 422},
    {"degenerate-transform", "Degenerate transform", 422},
    {"in-use", "Object in use", 422},
    {"cycle", "Group cycle", 422},
    {"empty-mesh", "Empty mesh", 422},
    {"invalid-asset", "Invalid asset", 422},
    {"version-mismatch", "Scene version mismatch", 412},
    {"not-found", "Not found", 404},
    {"method-not-allowed", "Method not allowed", 405},
    {"unauthorized", "Unauthorized", 401},
    {"unavailable", "Service unavailable", 503},
    {"deadline-exceeded", "Deadline exceeded", 503},
    {"request-timeout", "Request timeout", 408},
    {"uri-too-long", "URI too long", 414},
    {"unsupported-encoding", "Unsupported content encoding", 415},
    {"unsupported-media-type", "Unsupported media type", 415},
    {"expectation-failed", "Expectation failed", 417},
    {"too-many-connections", "Too many connections", 429},
    {"headers-too-large", "Request header fields too large", 431},
    {"not-implemented", "Not implemented", 501},
    {"http-version-not-supported", "HTTP version not supported", 505},
    {"internal", "Internal server error", 500},
};
static_assert(std::size(TYPES) == std::size_t(ProblemType::Internal) + 1);

ProblemType type_of(ErrorCode code) {
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
        case ErrorCode::Cancelled:
        case ErrorCode::Storage:  // the journal could not take the batch: nothing was applied
            return ProblemType::Unavailable;
        case ErrorCode::StaleHandle:
        case ErrorCode::Internal:
            return ProblemType::Internal;
    }
    return ProblemType::Internal;
}

/// The engine names array elements of `positions`/`indices`/`normals`/`uvs`; point at the member
/// the client used.
std::string wire_field(const std::string& field, const EditSource* src) {
    if (!src || field.empty()) return field;
    const std::string head = field.substr(0, field.find('/'));
    if (head == "positions" || head == "indices") {
        if (src->shape) return "shape";
        if (head == "positions" && src->positions_b64) return "positions_b64";
        if (head == "indices" && src->indices_b64) return "indices_b64";
    }
    if (head == "normals" && src->normals_b64) return "normals_b64";
    if (head == "uvs" && src->uvs_b64) return "uvs_b64";
    return field;
}

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

Problem make_problem(ProblemType type, std::string detail) {
    Problem p;
    p.type = type;
    p.status = problem_status(type);
    p.detail = std::move(detail);
    return p;
}

Problem problem_from(const RequestError& e) {
    ProblemType type = ProblemType::InvalidRequest;
    switch (e.kind) {
        case RequestErrorKind::Syntax:
            type = ProblemType::MalformedJson;
            break;
        case RequestErrorKind::TooDeep:
            type = ProblemType::NestingTooDeep;
            break;
        case RequestErrorKind::TooLarge:
            type = ProblemType::TooLarge;
            break;
        case RequestErrorKind::Schema:
            type = ProblemType::InvalidRequest;
            break;
        case RequestErrorKind::Value:
            type = type_of(e.code);
            break;
    }
    Problem p = make_problem(type, e.message);
    p.edit_index = e.edit_index;
    if (e.kind == RequestErrorKind::Schema || e.kind == RequestErrorKind::Value)
        p.pointer = e.pointer;
    if (!e.pointer.empty() && p.pointer) p.detail = e.pointer + ": " + e.message;
    return p;
}

Problem problem_from_batch_error(const Error& e, const std::vector<EditSource>& sources) {
    Problem p = make_problem(type_of(e.code), e.message);
    if (e.edit_index == Error::NO_INDEX) return p;
    p.edit_index = e.edit_index;
    const EditSource* src = e.edit_index < sources.size() ? &sources[e.edit_index] : nullptr;
    const std::string field = wire_field(e.field, src);
    p.pointer = "/edits/" + std::to_string(e.edit_index) + (field.empty() ? "" : "/" + field);
    p.detail = "edit " + std::to_string(e.edit_index) + " (" + *p.pointer + "): " + e.message;
    return p;
}

Problem problem_from(const Error& e) {
    Problem p = make_problem(type_of(e.code), e.message);
    if (!e.field.empty()) {
        p.pointer = "/" + e.field;
        p.detail = *p.pointer + ": " + e.message;
    }
    return p;
}

Json problem_to_json(const Problem& p) {
    Json j = {{"type", problem_type_uri(p.type)},
              {"title", problem_title(p.type)},
              {"status", p.status},
              {"detail", p.detail}};
    if (p.edit_index != Error::NO_INDEX) j["edit_index"] = p.edit_index;
    if (p.pointer) j["pointer"] = *p.pointer;
    if (p.file) j["file"] = *p.file;
    if (p.element) j["element"] = *p.element;
    return j;
}

}  // namespace strata::protocol

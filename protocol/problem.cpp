#include "protocol/problem.h"

#include "protocol/edit_parser.h"
#include "protocol/json_document.h"

namespace strata::protocol {

namespace {

/// The engine names array elements of `positions`, `indices` and the vertex attributes; point at
/// the member the client used.
std::string wire_field(const std::string& field, const EditSource* src) {
    if (!src || field.empty()) return field;
    const std::string head = field.substr(0, field.find('/'));
    if (head == "positions" || head == "indices") {
        if (src->shape) return "shape";
        if (head == "positions" && src->positions_b64) return "positions_b64";
        if (head == "indices" && src->indices_b64) return "indices_b64";
    }
    std::string b64;
    for_each_vertex_attribute([&](auto a) {
        if (head == decltype(a)::name && (src->attributes_b64 >> decltype(a)::index & 1u) != 0)
            b64 = head + "_b64";
    });
    if (!b64.empty()) return b64;
    if (head == "vertices" && src->vertices_b64) return "vertices_b64";
    if (head == "strands" && src->strands_b64) return "strands_b64";
    // A bulk edit's item in a packed form: the member (the message names the item).
    if (head == "ids" && src->ids_range) return "ids";
    if (head == "transforms" && src->transforms_b64) return "transforms_b64";
    if (head == "transforms" && src->transforms_flat) return "transforms";
    return field;
}

}  // namespace

Problem problem_from_batch_error(const Error& e, const std::vector<EditSource>& sources) {
    // The batch's own members (its message) are named by field alone.
    if (e.edit_index == Error::NO_INDEX && e.field == "message") return problem_from(e);
    Problem p = make_problem(problem_type_of(e.code), e.message);
    if (e.edit_index == Error::NO_INDEX) return p;
    p.edit_index = e.edit_index;
    const EditSource* src = e.edit_index < sources.size() ? &sources[e.edit_index] : nullptr;
    const std::string field = wire_field(e.field, src);
    p.pointer = "/edits/" + std::to_string(e.edit_index) + (field.empty() ? "" : "/" + field);
    p.detail = "edit " + std::to_string(e.edit_index) + " (" + *p.pointer + "): " + e.message;
    return p;
}

Problem problem_from(const Error& e) {
    Problem p = make_problem(problem_type_of(e.code), e.message);
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

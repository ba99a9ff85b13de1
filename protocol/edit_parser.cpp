#include "protocol/edit_parser.h"

#include "engine/core/check.h"
#include "protocol/edit_ops.h"
#include "protocol/edit_schema.h"

namespace strata::protocol {

namespace {

/// Dispatches on `op` through the op table: the op's schema members first, then its parser.
Edit parse_edit(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src) {
    if (!v.is_object()) r.schema_error(ptr, "an edit is an object with an \"op\" member");
    const Json& name = r.required(v, ptr, "op");
    if (const EditOp* op =
            name.is_string() ? find_edit_op(name.get_ref<const std::string&>()) : nullptr) {
        const MemberRule& members = edit_op_members(*op);
        r.expect_object(v, ptr, members);
        OpFields fields(r, v, ptr, members, src);
        Edit edit = op->parse(fields);
        STRATA_DCHECK((op->produces & edit_kind(edit)) != 0);
        return edit;
    }
    std::string list;
    for (const EditOp& op : edit_ops()) list += (list.empty() ? "" : ", ") + std::string(op.name);
    r.schema_error(child(ptr, "op"),
                   "unknown op" +
                       (name.is_string() ? " '" + name.get<std::string>() + "'" : std::string()) +
                       " (ops: " + list + ")");
}

/// Parses the whole batch; throws the first schema error, returns the first value error.
std::optional<Problem> parse_into(const Json& body, ParsedBatch& out) {
    static const MemberRule BATCH = schema_members("");
    FieldReader r;
    r.expect_object(body, "", BATCH);
    if (const Json* message = FieldReader::member(body, "message"))
        out.batch.info.message = r.text(*message, "/message");
    const Json& edits = r.required(body, "", "edits");
    if (!edits.is_array()) r.schema_error("/edits", "expected an array of edits");
    out.batch.edits.reserve(edits.size());
    out.sources.resize(edits.size());
    for (std::size_t i = 0; i < edits.size(); ++i) {
        r.set_edit_index(i);
        out.batch.edits.push_back(
            parse_edit(r, edits[i], "/edits/" + std::to_string(i), out.sources[i]));
    }
    return r.value_error();
}

}  // namespace

Parsed<ParsedBatch> parse_edit_batch(const Json& body) {
    ParsedBatch out;
    try {
        if (auto value_error = parse_into(body, out)) return Unexpected(std::move(*value_error));
    } catch (const RequestFailure& f) {
        return Unexpected(f.problem());
    }
    return out;
}

Parsed<ParsedBatch> parse_edit_batch(std::string_view text, const JsonLimits& limits,
                                     std::size_t max_edits) {
    auto doc = parse_json(text, limits);
    if (!doc) return Unexpected(doc.error());
    if (const auto it = doc->find("edits");
        doc->is_object() && it != doc->end() && it->is_array() && it->size() > max_edits) {
        Problem p =
            make_problem(ProblemType::TooLarge,
                         "the batch holds " + std::to_string(it->size()) + " edits, more than " +
                             std::to_string(max_edits) + " (--max-batch-edits): split it");
        p.pointer = "/edits";
        return Unexpected(std::move(p));
    }
    return parse_edit_batch(doc.value());
}

}  // namespace strata::protocol

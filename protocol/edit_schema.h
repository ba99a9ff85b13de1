#pragma once
// The JSON Schema of an edit batch (protocol/edit-batch.schema.json), generated from the op table:
// the envelope and the definitions ops share (id, u32, vec3, transform, shape, ...) are written
// once in edit_schema.cpp, each op's own fragment next to its parser (protocol/ops/). The parser
// takes the members it accepts from this document too, so a member is named in one place.
//
// tests/protocol/protocol_docs_test.cpp fails when the committed schema file differs from
// edit_batch_schema_text(), and rewrites it with STRATA_UPDATE_DOCS=1.

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "protocol/json_fields.h"

namespace strata::protocol {

/// A JSON document whose objects keep their members in written order (schemas read better so).
using OrderedJson = nlohmann::ordered_json;

/// The whole edit-batch schema (draft 2020-12), built once from the op table.
const OrderedJson& edit_batch_schema();

/// edit_batch_schema() as the text of protocol/edit-batch.schema.json.
std::string edit_batch_schema_text();

/// The members of the object schema at JSON pointer `pointer` in edit_batch_schema(). A pointer
/// that names no object schema is a bug in Strata (checked).
MemberRule schema_members(std::string_view pointer);

}  // namespace strata::protocol

#pragma once
// The binary form of an edit batch, shared by journal records and snapshots: a u32 edit count
// (its top bit set when the batch's info follows: kind, target version, time and message), then per
// edit a one-byte kind tag and its fields (byte_io.h). Bulk vertex and index arrays are
// raw little-endian buffers. The layout of each kind is written once, in edit_codec.cpp.

#include <functional>
#include <string>
#include <string_view>

#include "engine/core/result.h"
#include "engine/scene/edits.h"

namespace strata::durable {

/// The wire name of edit kind `index` (the Edit variant's index): "add_mesh", "set_transform"...
const char* edit_kind_name(std::size_t index);

/// The number of edits a batch's bytes announce, read from its count alone (0 when the bytes are
/// too short): what a reader checks against its limit before decoding anything.
uint32_t edit_count(std::string_view bytes);

/// Appends the batch's binary form to `out`.
void encode_batch(const EditBatch& batch, std::string& out);

/// Reads a whole batch back; the input must hold exactly one. An error (InvalidArgument) names
/// the edit and the byte offset where decoding failed.
Result<EditBatch> decode_batch(std::string_view bytes);

/// The same, one edit at a time: each decoded edit goes to `sink` as soon as it is read (a
/// snapshot restore loads it straight into the scene; no whole batch is held). A decoding error
/// names the edit and offset like decode_batch's; the sink's first error stops decoding and comes
/// back with the edit's index set.
/// The batch's info, when it has one, goes to `info` (when given).
Status decode_each(std::string_view bytes, const std::function<Status(Edit&&)>& sink,
                   BatchInfo* info = nullptr);

}  // namespace strata::durable

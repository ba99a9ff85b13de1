#pragma once
// JSON edit batches -> engine EditBatch. `{"edits": [{"op": "add_mesh", ...}, ...]}`; the ops are
// listed in edit_ops.h (each op's parser and schema live in protocol/ops/), documented in
// protocol/README.md and described by protocol/edit-batch.schema.json, generated from that list.
//
// Two stages in one pass: structural checks (exactly what the JSON Schema says: types, required
// and unknown members, enums, ranges) throw at the first problem; value checks (numbers that do
// not fit a float, arrays whose length is not a multiple of 3, ...) are reported only when the
// structure is sound. Checks against the scene (unknown ids, ...) are the engine's, at apply.

#include <string_view>
#include <vector>

#include "engine/scene/edits.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// Which wire members an edit's arrays came from, to point engine errors at the right member.
struct EditSource {
    bool positions_b64 = false;
    bool indices_b64 = false;
    /// Bit `A::index` per vertex attribute A (vertex_attributes.h) given as base64.
    uint8_t attributes_b64 = 0;
    bool vertices_b64 = false;
    bool strands_b64 = false;
    bool shape = false;
    bool ids_range = false;  ///< bulk ids given as a numbered range
    bool transforms_b64 = false;
    bool transforms_flat = false;  ///< bulk transforms as flat numbers, 12 per item
};

/// A parsed batch and, parallel to its edits, where their arrays came from.
struct ParsedBatch {
    EditBatch batch;
    std::vector<EditSource> sources;
};

/// Largest `segments` of a sphere shape and `subdivisions` of a plane shape.
constexpr uint32_t MAX_SPHERE_SEGMENTS = 2048;
constexpr uint32_t MAX_PLANE_SUBDIVISIONS = 1024;

/// Most edits one batch may hold, by default (--max-batch-edits): a batch's edits are 250 bytes
/// each in memory, beside their JSON or snapshot bytes.
constexpr std::size_t DEFAULT_MAX_BATCH_EDITS = std::size_t(1) << 20;

/// Parses a batch document.
Parsed<ParsedBatch> parse_edit_batch(const Json& body);
/// Parses a batch from request text; one of more than `max_edits` edits is TooLarge at /edits,
/// refused before any edit is built.
Parsed<ParsedBatch> parse_edit_batch(std::string_view text, const JsonLimits& limits,
                                     std::size_t max_edits = DEFAULT_MAX_BATCH_EDITS);

}  // namespace strata::protocol

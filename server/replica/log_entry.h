#pragma once
// One entry of the shared edit log: a journal record (engine/durable/journal_format.h)
//   u32 payload length | u32 crc32c(payload, then the version's 8 bytes) | u64 version | payload
// whose payload is an edit batch (edit_codec.h). The stream entry carries it in its field "r";
// the entry's id is "<version>-0", so the stream orders entries by version and XTRIM MINID cuts
// at a version.

#include <cstdint>
#include <string>
#include <string_view>

#include "engine/core/result.h"
#include "engine/scene/edits.h"

namespace strata::replica {

/// A checked entry; `payload` points into the bytes it was read from.
struct LogEntry {
    uint64_t version = 0;
    std::string_view payload;
};

/// The bytes of a batch that produces `version`.
std::string encode_entry(const EditBatch& batch, uint64_t version);

/// An encoded batch (edit_codec.h) restamped for `version`: the payload is reused as it is.
std::string restamp_entry(std::string_view entry, uint64_t version);

/// Checks length and checksum; errors (InvalidArgument) say what is wrong.
Result<LogEntry> decode_entry(std::string_view bytes);

/// The stream entry id of a version: "<version>-0".
std::string entry_id(uint64_t version);

}  // namespace strata::replica

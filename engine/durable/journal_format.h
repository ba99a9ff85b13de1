#pragma once
// The on-disk layout of journal segments and snapshots (little-endian throughout).
//
// A journal segment `journal-<base>.log` (base zero-padded to 20 digits) is a 32-byte header
//   "STRATAJ1" | u32 format (1) | u32 0 | u64 base version | u32 crc32c(first 24 bytes) | u32 0
// followed by records, each
//   u32 payload length | u32 crc32c(payload, then the version's 8 bytes) | u64 version | payload
// where the payload is an edit batch (edit_codec.h) and the version is the one the batch
// produced. Records of one segment are consecutive versions from base + 1.
//
// A snapshot `snapshot-<version>.snap` (and the body of GET /v1/scene/snapshot) is a 32-byte
// header
//   "STRATAS1" | u32 format (1) | u32 crc32c(payload) | u64 version | u64 payload length
// followed by the payload: an edit batch that builds the scene from an empty one.
//
// Beside a snapshot, `history-<version>.hist` keeps the scene's history at that version (so that
// undo reaches past the snapshot after a restart): the same header with the magic "STRATAH1",
// followed by the entries, the undo stack and the redo stack (each step's batch as edit_codec.h
// writes it). A history file that is missing or damaged costs the history before its snapshot,
// never the scene.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"
#include "engine/scene/edit_history.h"
#include "engine/scene/edits.h"

namespace strata::durable {

inline constexpr std::size_t SEGMENT_HEADER_BYTES = 32;
inline constexpr std::size_t RECORD_HEADER_BYTES = 16;
inline constexpr std::size_t SNAPSHOT_HEADER_BYTES = 32;
inline constexpr uint32_t FORMAT_VERSION = 1;

/// `journal-<base>.log` / `snapshot-<version>.snap` names, and their parsers (false: not ours).
std::string segment_name(uint64_t base);
std::string snapshot_name(uint64_t version);
std::string history_name(uint64_t version);
bool parse_segment_name(std::string_view name, uint64_t& base);
bool parse_snapshot_name(std::string_view name, uint64_t& version);
bool parse_history_name(std::string_view name, uint64_t& version);

/// A segment header for records after `base`.
std::string segment_header(uint64_t base);

/// A record's bytes before its version is known: header space, then the batch. The payload's
/// checksum is computed here, outside any lock; stamp_record() finishes it cheaply.
struct PendingRecord {
    std::string bytes;
    uint32_t payload_crc = 0;
};
PendingRecord prepare_record(const EditBatch& batch);
/// Writes the length, version and checksum into the header of `r`.
void stamp_record(PendingRecord& r, uint64_t version);

/// One record found in a segment; `payload` points into the scanned bytes.
struct ScannedRecord {
    uint64_t offset = 0;
    uint64_t version = 0;
    std::string_view payload;
};

/// What scanning a segment found.
struct SegmentScan {
    uint64_t base = 0;
    std::vector<ScannedRecord> records;
    uint64_t valid_end = 0;  ///< bytes up to the end of the last good record (or the header)
    enum class Tail : uint8_t {
        Clean,    ///< the file ends exactly after a good record (or the header)
        Torn,     ///< the last record is incomplete or fails its checksum and nothing follows it
        Corrupt,  ///< a bad record (or header) with more data after it
    } tail = Tail::Clean;
    bool empty_file = false;  ///< zero bytes (a crash right after creating the file)
    std::string problem;      ///< for Torn and Corrupt: what is wrong, at which offset
};
/// Checks the header and every record of a segment's bytes.
SegmentScan scan_segment(std::string_view bytes);

/// A snapshot file's bytes for a scene at `version` built by `scene`.
std::string encode_snapshot(const EditBatch& scene, uint64_t version);
/// A snapshot's scene batch and version; errors name the byte offset of what is wrong.
struct DecodedSnapshot {
    uint64_t version = 0;
    EditBatch scene;
};
Result<DecodedSnapshot> decode_snapshot(std::string_view bytes);

/// A snapshot's header checked (magic, format, length, checksum) without decoding its scene:
/// the version, and the payload (edit_codec.h's batch bytes) pointing into `bytes`.
struct SnapshotView {
    uint64_t version = 0;
    std::string_view payload;
};
Result<SnapshotView> open_snapshot(std::string_view bytes);

/// A history file's bytes for the history `state` of the scene at `version`.
std::string encode_history(const HistoryState& state, uint64_t version);
/// A history file's history and version; errors say what is wrong and where.
struct DecodedHistory {
    uint64_t version = 0;
    HistoryState state;
};
Result<DecodedHistory> decode_history(std::string_view bytes);

}  // namespace strata::durable

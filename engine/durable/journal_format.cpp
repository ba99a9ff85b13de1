#include "engine/durable/journal_format.h"

#include <charconv>
#include <cstdio>
#include <cstring>

#include "engine/durable/byte_io.h"
#include "engine/durable/crc32c.h"
#include "engine/durable/edit_codec.h"

namespace strata::durable {

namespace {

constexpr char SEGMENT_MAGIC[8] = {'S', 'T', 'R', 'A', 'T', 'A', 'J', '1'};
constexpr char SNAPSHOT_MAGIC[8] = {'S', 'T', 'R', 'A', 'T', 'A', 'S', '1'};
constexpr char HISTORY_MAGIC[8] = {'S', 'T', 'R', 'A', 'T', 'A', 'H', '1'};

template <class T>
void put(std::string& out, std::size_t at, T v) {
    std::memcpy(out.data() + at, &v, sizeof v);
}
template <class T>
T get(std::string_view in, std::size_t at) {
    T v;
    std::memcpy(&v, in.data() + at, sizeof v);
    return v;
}

std::string numbered(const char* prefix, uint64_t n, const char* suffix) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%s%020llu%s", prefix, static_cast<unsigned long long>(n),
                  suffix);
    return buffer;
}

bool parse_numbered(std::string_view name, std::string_view prefix, std::string_view suffix,
                    uint64_t& n) {
    if (name.size() != prefix.size() + 20 + suffix.size()) return false;
    if (name.substr(0, prefix.size()) != prefix) return false;
    if (name.substr(name.size() - suffix.size()) != suffix) return false;
    const char* first = name.data() + prefix.size();
    const auto [end, ec] = std::from_chars(first, first + 20, n);
    return ec == std::errc() && end == first + 20;
}

std::string at(uint64_t offset) {
    return " at offset " + std::to_string(offset);
}

}  // namespace

std::string segment_name(uint64_t base) {
    return numbered("journal-", base, ".log");
}
std::string snapshot_name(uint64_t version) {
    return numbered("snapshot-", version, ".snap");
}
std::string history_name(uint64_t version) {
    return numbered("history-", version, ".hist");
}
bool parse_segment_name(std::string_view name, uint64_t& base) {
    return parse_numbered(name, "journal-", ".log", base);
}
bool parse_snapshot_name(std::string_view name, uint64_t& version) {
    return parse_numbered(name, "snapshot-", ".snap", version);
}
bool parse_history_name(std::string_view name, uint64_t& version) {
    return parse_numbered(name, "history-", ".hist", version);
}

std::string segment_header(uint64_t base) {
    std::string h(SEGMENT_HEADER_BYTES, '\0');
    std::memcpy(h.data(), SEGMENT_MAGIC, 8);
    put<uint32_t>(h, 8, FORMAT_VERSION);
    put<uint64_t>(h, 16, base);
    put<uint32_t>(h, 24, crc32c(h.data(), 24));
    return h;
}

PendingRecord prepare_record(const EditBatch& batch) {
    PendingRecord r;
    r.bytes.assign(RECORD_HEADER_BYTES, '\0');
    encode_batch(batch, r.bytes);
    r.payload_crc =
        crc32c(r.bytes.data() + RECORD_HEADER_BYTES, r.bytes.size() - RECORD_HEADER_BYTES);
    return r;
}

void stamp_record(PendingRecord& r, uint64_t version) {
    put<uint32_t>(r.bytes, 0, uint32_t(r.bytes.size() - RECORD_HEADER_BYTES));
    put<uint32_t>(r.bytes, 4, crc32c(&version, sizeof version, r.payload_crc));
    put<uint64_t>(r.bytes, 8, version);
}

SegmentScan scan_segment(std::string_view bytes) {
    SegmentScan scan;
    // Step: the header. A file shorter than a header is a crash during its creation.
    if (bytes.empty()) {
        scan.empty_file = true;
        return scan;
    }
    if (bytes.size() < SEGMENT_HEADER_BYTES) {
        scan.tail = SegmentScan::Tail::Torn;
        scan.problem = "the header is incomplete (" + std::to_string(bytes.size()) + " bytes)";
        return scan;
    }
    if (std::memcmp(bytes.data(), SEGMENT_MAGIC, 8) != 0 ||
        get<uint32_t>(bytes, 24) != crc32c(bytes.data(), 24)) {
        scan.tail = SegmentScan::Tail::Corrupt;
        scan.problem = "not a Strata journal header (bad magic or checksum) at offset 0";
        return scan;
    }
    if (get<uint32_t>(bytes, 8) != FORMAT_VERSION) {
        scan.tail = SegmentScan::Tail::Corrupt;
        scan.problem = "journal format " + std::to_string(get<uint32_t>(bytes, 8)) +
                       " is not supported (this server reads format 1)";
        return scan;
    }
    scan.base = get<uint64_t>(bytes, 16);
    // Step: records, until the end or the first bad one.
    uint64_t pos = SEGMENT_HEADER_BYTES;
    scan.valid_end = pos;
    while (pos < bytes.size()) {
        const uint64_t left = bytes.size() - pos;
        if (left < RECORD_HEADER_BYTES) {
            scan.tail = SegmentScan::Tail::Torn;
            scan.problem = "incomplete record header" + at(pos);
            return scan;
        }
        const uint32_t length = get<uint32_t>(bytes, pos);
        const uint32_t crc = get<uint32_t>(bytes, pos + 4);
        const uint64_t version = get<uint64_t>(bytes, pos + 8);
        if (RECORD_HEADER_BYTES + uint64_t(length) > left) {
            scan.tail = SegmentScan::Tail::Torn;
            scan.problem = "record of " + std::to_string(length) +
                           " bytes runs past the end of the file" + at(pos);
            return scan;
        }
        const std::string_view payload = bytes.substr(pos + RECORD_HEADER_BYTES, length);
        const uint64_t end = pos + RECORD_HEADER_BYTES + length;
        if (crc32c(&version, sizeof version, crc32c(payload.data(), payload.size())) != crc) {
            // The last record failing its checksum is a torn write; anything after it means the
            // damage is in the middle of the journal.
            scan.tail = end == bytes.size() ? SegmentScan::Tail::Torn : SegmentScan::Tail::Corrupt;
            scan.problem = "record checksum mismatch" + at(pos);
            return scan;
        }
        scan.records.push_back({pos, version, payload});
        pos = end;
        scan.valid_end = pos;
    }
    return scan;
}

namespace {

/// `payload` behind a 32-byte header: `magic`, the format, its checksum, `version`, its length.
std::string framed(const char (&magic)[8], uint64_t version, std::string payload) {
    std::string out(SNAPSHOT_HEADER_BYTES, '\0');
    out += payload;
    std::memcpy(out.data(), magic, 8);
    put<uint32_t>(out, 8, FORMAT_VERSION);
    put<uint32_t>(out, 12, crc32c(payload.data(), payload.size()));
    put<uint64_t>(out, 16, version);
    put<uint64_t>(out, 24, payload.size());
    return out;
}

/// The version and payload of a file framed with `magic`; `what` names the kind in errors.
Result<SnapshotView> unframed(std::string_view bytes, const char (&magic)[8], const char* what) {
    const std::string kind(what);
    if (bytes.size() < SNAPSHOT_HEADER_BYTES || std::memcmp(bytes.data(), magic, 8) != 0)
        return failure(ErrorCode::InvalidArgument, "not a Strata " + kind + " (it must start with '" +
                                                       std::string(magic, 8) +
                                                       "' and a 32-byte header)");
    if (get<uint32_t>(bytes, 8) != FORMAT_VERSION)
        return failure(ErrorCode::InvalidArgument,
                       kind + " format " + std::to_string(get<uint32_t>(bytes, 8)) +
                           " is not supported (this server reads format 1)");
    const uint64_t length = get<uint64_t>(bytes, 24);
    if (length != bytes.size() - SNAPSHOT_HEADER_BYTES)
        return failure(ErrorCode::InvalidArgument,
                       kind + " payload should be " + std::to_string(length) + " bytes but " +
                           std::to_string(bytes.size() - SNAPSHOT_HEADER_BYTES) +
                           " follow the header (truncated or padded)");
    const std::string_view payload = bytes.substr(SNAPSHOT_HEADER_BYTES);
    if (crc32c(payload.data(), payload.size()) != get<uint32_t>(bytes, 12))
        return failure(ErrorCode::InvalidArgument,
                       kind + " checksum mismatch in the payload at offset 32 (the file is "
                              "damaged)");
    return SnapshotView{get<uint64_t>(bytes, 16), payload};
}

void put_steps(ByteWriter& w, const std::vector<HistoryState::Step>& steps) {
    w(uint64_t(steps.size()));
    for (const HistoryState::Step& s : steps) {
        std::string batch;
        encode_batch(*s.batch, batch);
        w(s.version, batch);
    }
}

void get_steps(ByteReader& r, std::vector<HistoryState::Step>& steps) {
    uint64_t n = 0;
    r(n);
    // A step takes at least its version and its batch's length.
    if (r.ok() && n > r.remaining() / 12) return r.fail("step count " + std::to_string(n));
    for (uint64_t i = 0; i < n && r.ok(); ++i) {
        HistoryState::Step s;
        std::string bytes;
        r(s.version, bytes);
        if (!r.ok()) return;
        auto batch = decode_batch(bytes);
        if (!batch) return r.fail("step " + std::to_string(i) + ": " + batch.error().message);
        s.batch = std::make_shared<const EditBatch>(std::move(batch.value()));
        steps.push_back(std::move(s));
    }
}

}  // namespace

std::string encode_snapshot(const EditBatch& scene, uint64_t version) {
    std::string payload;
    encode_batch(scene, payload);
    return framed(SNAPSHOT_MAGIC, version, std::move(payload));
}

Result<SnapshotView> open_snapshot(std::string_view bytes) {
    return unframed(bytes, SNAPSHOT_MAGIC, "snapshot");
}

std::string encode_history(const HistoryState& state, uint64_t version) {
    std::string payload;
    ByteWriter w(payload);
    w(uint64_t(state.entries.size()));
    for (const HistoryEntry& e : state.entries) {
        w(e.version, e.info.kind, e.info.target, e.info.time_ms, e.info.message, e.edits,
          uint64_t(e.ops.size()));
        for (const auto& [kind, count] : e.ops) w(kind, count);
    }
    put_steps(w, state.undo);
    put_steps(w, state.redo);
    return framed(HISTORY_MAGIC, version, std::move(payload));
}

Result<DecodedHistory> decode_history(std::string_view bytes) {
    auto view = unframed(bytes, HISTORY_MAGIC, "history file");
    if (!view) return Unexpected(view.error());
    DecodedHistory out{view->version, {}};
    ByteReader r(view->payload);
    uint64_t n = 0;
    r(n);
    // An entry takes at least its 33 fixed bytes.
    if (r.ok() && n > r.remaining() / 33) r.fail("entry count " + std::to_string(n));
    for (uint64_t i = 0; i < n && r.ok(); ++i) {
        HistoryEntry e;
        uint64_t ops = 0;
        r(e.version, e.info.kind, e.info.target, e.info.time_ms, e.info.message, e.edits, ops);
        if (r.ok() && ops > r.remaining() / 5) r.fail("op count " + std::to_string(ops));
        for (uint64_t k = 0; k < ops && r.ok(); ++k) {
            std::pair<uint8_t, uint32_t> op;
            r(op.first, op.second);
            e.ops.push_back(op);
        }
        out.state.entries.push_back(std::move(e));
    }
    get_steps(r, out.state.undo);
    get_steps(r, out.state.redo);
    if (r.ok() && r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " bytes left over");
    if (!r.ok()) return failure(ErrorCode::InvalidArgument, "history file payload: " + r.error());
    return out;
}

Result<DecodedSnapshot> decode_snapshot(std::string_view bytes) {
    auto view = open_snapshot(bytes);
    if (!view) return Unexpected(view.error());
    auto scene = decode_batch(view->payload);
    if (!scene) return failure(ErrorCode::InvalidArgument, "snapshot " + scene.error().message);
    return DecodedSnapshot{view->version, std::move(scene.value())};
}

}  // namespace strata::durable

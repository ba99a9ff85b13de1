#include "server/replica/log_entry.h"

#include <cstring>

#include "engine/durable/crc32c.h"
#include "engine/durable/journal_format.h"

namespace strata::replica {

namespace {

template <class T>
T get(std::string_view in, std::size_t at) {
    T v;
    std::memcpy(&v, in.data() + at, sizeof v);
    return v;
}

}  // namespace

std::string encode_entry(const EditBatch& batch, uint64_t version) {
    durable::PendingRecord r = durable::prepare_record(batch);
    durable::stamp_record(r, version);
    return std::move(r.bytes);
}

std::string restamp_entry(std::string_view entry, uint64_t version) {
    durable::PendingRecord r;
    r.bytes = std::string(entry);
    const std::string_view payload = entry.substr(durable::RECORD_HEADER_BYTES);
    r.payload_crc = durable::crc32c(payload.data(), payload.size());
    durable::stamp_record(r, version);
    return std::move(r.bytes);
}

Result<LogEntry> decode_entry(std::string_view bytes) {
    constexpr std::size_t HEADER = durable::RECORD_HEADER_BYTES;
    if (bytes.size() < HEADER)
        return failure(ErrorCode::InvalidArgument, "log entry of " + std::to_string(bytes.size()) +
                                                       " bytes is shorter than its 16-byte header");
    const uint32_t length = get<uint32_t>(bytes, 0);
    const uint32_t crc = get<uint32_t>(bytes, 4);
    const uint64_t version = get<uint64_t>(bytes, 8);
    if (uint64_t(length) != bytes.size() - HEADER)
        return failure(ErrorCode::InvalidArgument,
                       "log entry says its payload has " + std::to_string(length) + " bytes but " +
                           std::to_string(bytes.size() - HEADER) + " follow");
    const std::string_view payload = bytes.substr(HEADER);
    if (durable::crc32c(&version, sizeof version,
                        durable::crc32c(payload.data(), payload.size())) != crc)
        return failure(ErrorCode::InvalidArgument,
                       "log entry of version " + std::to_string(version) +
                           " fails its checksum (damaged in transit or in Redis)");
    return LogEntry{version, payload};
}

std::string entry_id(uint64_t version) {
    return std::to_string(version) + "-0";
}

}  // namespace strata::replica

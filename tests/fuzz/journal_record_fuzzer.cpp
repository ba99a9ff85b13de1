// libFuzzer target for the journal's decoders, which recovery runs on whatever the disk holds:
// the segment framing (scan_segment: header, record lengths, checksums, torn and corrupt tails)
// and the edit-batch codec of each record's payload (decode_batch).
//
// Each input is read both ways: as a whole segment file, and as one record's payload. Checks,
// besides "no crash, no sanitizer report":
//   - the scan stays inside the input, its records are in order and end where valid_end says;
//   - a payload that decodes is canonical (re-encodes to the same bytes) and goes through the
//     scene's rules; a refused batch leaves the scene untouched (durable_fuzz_util.h).
// Seeds are written by the encoder itself (durable_corpus.cpp); build and run: scripts/run-fuzz.sh.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "engine/durable/journal_format.h"
#include "tests/fuzz/durable_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata;
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);

    // Step: the bytes as one record's payload.
    fuzz::check_batch_payload(bytes);

    // Step: the bytes as a segment file.
    const durable::SegmentScan scan = durable::scan_segment(bytes);
    FUZZ_CHECK(scan.valid_end <= size);
    uint64_t end = durable::SEGMENT_HEADER_BYTES;
    for (const durable::ScannedRecord& r : scan.records) {
        FUZZ_CHECK(r.offset == end);
        FUZZ_CHECK(r.payload.data() == bytes.data() + r.offset + durable::RECORD_HEADER_BYTES);
        end = r.offset + durable::RECORD_HEADER_BYTES + r.payload.size();
        FUZZ_CHECK(end <= size);
        fuzz::check_batch_payload(r.payload);
    }
    if (!scan.records.empty()) FUZZ_CHECK(scan.valid_end == end);
    if (scan.tail == durable::SegmentScan::Tail::Clean && !scan.empty_file)
        FUZZ_CHECK(scan.valid_end == size);
    return 0;
}

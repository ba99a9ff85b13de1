#pragma once
// A reader of POSIX ustar archives (what `tar cf` writes, GNU long names and pax `path` records
// included) over bytes already in memory: an entry is a byte range of the body, nothing touches
// the filesystem. Made for untrusted uploads: every header's checksum and octal fields are
// checked against the body, names are normalised and refused when absolute or when they climb
// with "..", links and devices are refused, entries and bytes are bounded.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// One regular file of an archive.
struct TarEntry {
    std::string path;                ///< normal form: "a/b.png" (no "./", no "//", no "..")
    std::span<const uint8_t> bytes;  ///< a view into the archive's bytes
    uint64_t header_offset = 0;      ///< where its (first) header starts, for messages
};

/// What one archive may hold.
struct TarLimits {
    uint32_t max_entries = 4096;              ///< headers of any kind, directories included
    uint64_t max_total_bytes = 256ull << 20;  ///< sum of the regular files' sizes
};

/// Reads every regular file of a ustar archive; directories and pax global headers are skipped.
/// `archive` names the upload in errors, whose element names the entry ("entry 'a/b.png'") or,
/// before a name is known, the header's byte offset. Refused: a bad checksum, a field that is not
/// octal, data past the end of the body, a missing end-of-archive block, an absolute name or one
/// with "..", a hard or symbolic link, a device or FIFO, an unknown entry type, two entries with
/// the same name, more than `limits` allow (TooLarge).
Imported<std::vector<TarEntry>> read_tar(std::span<const uint8_t> body, const std::string& archive,
                                         const TarLimits& limits = {});

/// `name` with bytes outside printable ASCII as '?', at most 200 bytes: safe in any message.
std::string printable_name(std::string_view name);

}  // namespace strata::assets

#include "protocol/assets/tar_reader.h"

#include <cstring>
#include <optional>
#include <set>
#include <string_view>
#include <utility>

namespace strata::assets {

namespace {

constexpr uint64_t BLOCK = 512;
/// A GNU long name or a pax header larger than this is refused before it is read.
constexpr uint64_t MAX_META_BYTES = 64 * 1024;

/// Header field offsets and lengths (POSIX.1-1988 ustar).
struct Field {
    std::size_t offset, length;
};
constexpr Field NAME{0, 100}, SIZE{124, 12}, CHECKSUM{148, 8}, LINKNAME{157, 100}, MAGIC{257, 6},
    PREFIX{345, 155};
constexpr std::size_t TYPEFLAG = 156;

std::string_view text(const uint8_t* header, Field f) {
    const char* begin = reinterpret_cast<const char*>(header) + f.offset;
    const void* nul = std::memchr(begin, 0, f.length);
    return {begin, nul ? std::size_t(static_cast<const char*>(nul) - begin) : f.length};
}

/// An octal number field (leading spaces, digits, then spaces or NULs), or GNU's base-256 form
/// (high bit of the first byte set). nullopt when malformed, negative or over 2^63.
std::optional<uint64_t> number(const uint8_t* header, Field f) {
    const uint8_t* p = header + f.offset;
    uint64_t value = 0;
    if (p[0] & 0x80) {
        if (p[0] & 0x40) return std::nullopt;  // negative
        value = p[0] & 0x3f;
        for (std::size_t i = 1; i < f.length; ++i) {
            if (value > (uint64_t(1) << 55)) return std::nullopt;
            value = (value << 8) | p[i];
        }
        return value;
    }
    std::size_t i = 0;
    while (i < f.length && p[i] == ' ') ++i;
    const std::size_t first_digit = i;
    for (; i < f.length && p[i] >= '0' && p[i] <= '7'; ++i) {
        if (value > (uint64_t(1) << 60)) return std::nullopt;
        value = value * 8 + uint64_t(p[i] - '0');
    }
    if (i == first_digit) return std::nullopt;
    for (; i < f.length; ++i)
        if (p[i] != ' ' && p[i] != 0) return std::nullopt;
    return value;
}

bool all_zero(const uint8_t* block) {
    for (uint64_t i = 0; i < BLOCK; ++i)
        if (block[i] != 0) return false;
    return true;
}

/// The header's sums with the checksum field read as spaces: unsigned (POSIX) and signed (what
/// some old writers stored).
std::pair<int64_t, int64_t> header_sums(const uint8_t* header) {
    int64_t u = 0, s = 0;
    for (std::size_t i = 0; i < BLOCK; ++i) {
        const bool in_field = i >= CHECKSUM.offset && i < CHECKSUM.offset + CHECKSUM.length;
        const uint8_t b = in_field ? uint8_t(' ') : header[i];
        u += b;
        s += static_cast<int8_t>(b);
    }
    return {u, s};
}

/// The value of a pax extended header's "path" record, "" when it has none; nullopt when the
/// records are malformed. `size_record` is set when a "size" record is present.
std::optional<std::string> pax_path(std::string_view records, bool& size_record) {
    std::string path;
    while (!records.empty()) {
        // Each record: "<length> <key>=<value>\n", the length counting the whole record.
        std::size_t i = 0, length = 0;
        while (i < records.size() && i < 8 && records[i] >= '0' && records[i] <= '9')
            length = length * 10 + std::size_t(records[i++] - '0');
        if (i == 0 || i >= records.size() || records[i] != ' ' || length <= i + 1 ||
            length > records.size() || records[length - 1] != '\n')
            return std::nullopt;
        const std::string_view record = records.substr(i + 1, length - i - 2);
        const std::size_t eq = record.find('=');
        if (eq == std::string_view::npos) return std::nullopt;
        const std::string_view key = record.substr(0, eq);
        if (key == "path") path = std::string(record.substr(eq + 1));
        if (key == "size") size_record = true;
        records.remove_prefix(length);
    }
    return path;
}

/// `raw` in normal form, or the reason it is refused.
struct NormalName {
    std::string path;
    std::string refusal;
};
NormalName normalize_entry_name(std::string_view raw) {
    if (raw.empty()) return {"", "has an empty name"};
    if (raw.front() == '/') return {"", "has an absolute path (refused)"};
    for (char c : raw)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            return {"", "has a control character in its name"};
    std::string out;
    std::string_view rest = raw;
    while (!rest.empty()) {
        const std::size_t slash = rest.find('/');
        const std::string_view part = rest.substr(0, slash);
        rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
        if (part.empty() || part == ".") continue;
        if (part == "..") return {"", "climbs out of the archive with '..' (refused)"};
        if (!out.empty()) out += '/';
        out += part;
    }
    if (out.empty()) return {"", "names no file"};
    return {out, ""};
}

std::string entry_label(std::string_view name) {
    return "entry '" + printable_name(name) + "'";
}

}  // namespace

std::string printable_name(std::string_view name) {
    std::string out;
    for (char c : name.substr(0, 200)) {
        const auto u = static_cast<unsigned char>(c);
        out += u >= 0x20 && u < 0x7f ? c : '?';
    }
    if (name.size() > 200) out += "...";
    return out;
}

namespace {

/// One header and the data it announces.
struct TarHeader {
    const uint8_t* block = nullptr;
    char type = '0';
    std::string at;        ///< "header at byte N"
    std::string raw_name;  ///< as stored (prefix, long name and all)
    std::string where;     ///< the entry's label, or `at` while it has no name
    uint64_t size = 0;
    uint64_t offset = 0;  ///< of the header block
    std::span<const uint8_t> data;
};

/// What a header's type means for the walk.
enum class Step : uint8_t { Keep, Skip, End };

/// Walks an archive's headers in order.
class TarWalk {
public:
    TarWalk(std::span<const uint8_t> body, const std::string& archive, const TarLimits& limits)
        : m_body(body), m_sink(archive), m_limits(limits) {}

    Imported<std::vector<TarEntry>> run() {
        for (;;) {
            TarHeader h;
            auto step = next_header(h);
            if (!step) return Unexpected(step.error());
            if (step.value() == Step::End) break;
            if (step = by_type(h); !step) return Unexpected(step.error());
            if (step.value() == Step::Skip) continue;
            if (auto ok = keep(h); !ok) return Unexpected(ok.error());
        }
        return std::move(m_entries);
    }

private:
    /// Step 1: one header block, or the end-of-archive block; then its checksum, magic and
    /// size, each against the body.
    Imported<Step> next_header(TarHeader& h) {
        const uint64_t size = m_body.size();
        h.offset = m_offset;
        h.at = "header at byte " + std::to_string(m_offset);
        const std::string& at = h.at;
        if (m_offset == size)
            return m_sink.invalid(at,
                                  "the archive ends without its end-of-archive block "
                                  "(truncated?)");
        if (size - m_offset < BLOCK)
            return m_sink.invalid(at, "the archive ends inside a header (truncated?)");
        h.block = m_body.data() + m_offset;
        if (all_zero(h.block)) {
            if (m_long_name)
                return m_sink.invalid(at, "a long name ('" + printable_name(*m_long_name) +
                                              "') with no entry after it");
            return Step::End;
        }
        if (++m_headers > m_limits.max_entries)
            return m_sink.too_large(at, "more than " + std::to_string(m_limits.max_entries) +
                                            " entries in one archive");
        if (auto ok = check_header(h); !ok) return Unexpected(ok.error());
        const auto entry_size = number(h.block, SIZE);
        if (!entry_size) return m_sink.invalid(h.where, "its size field is not an octal number");
        const uint64_t data_offset = m_offset + BLOCK;
        const uint64_t left = size - data_offset;
        if (*entry_size > left)
            return m_sink.invalid(h.where, "its size (" + std::to_string(*entry_size) +
                                               " bytes) runs past the end of the archive (" +
                                               std::to_string(left) + " bytes left; truncated?)");
        const uint64_t padded = (*entry_size + BLOCK - 1) / BLOCK * BLOCK;
        if (padded > left)
            return m_sink.invalid(h.where, "the archive ends inside its last block (truncated?)");
        h.size = *entry_size;
        h.data = m_body.subspan(data_offset, *entry_size);
        m_offset = data_offset + padded;
        return Step::Keep;
    }

    /// The checksum and the magic; the entry's type and name.
    Imported<void> check_header(TarHeader& h) {
        const auto stored = number(h.block, CHECKSUM);
        const auto [unsigned_sum, signed_sum] = header_sums(h.block);
        if (!stored)
            return m_sink.invalid(h.at,
                                  "its checksum field is not an octal number (not a tar "
                                  "archive?)");
        if (int64_t(*stored) != unsigned_sum && int64_t(*stored) != signed_sum)
            return m_sink.invalid(h.at, "header checksum mismatch: it says " +
                                            std::to_string(*stored) + ", the header sums to " +
                                            std::to_string(unsigned_sum) +
                                            " (damaged, or not a tar archive)");
        if (text(h.block, {MAGIC.offset, 5}) != "ustar")
            return m_sink.invalid(h.at,
                                  "not a ustar header (only POSIX ustar, pax and GNU tar "
                                  "archives are read)");
        h.type = char(h.block[TYPEFLAG]);
        h.raw_name = std::string(text(h.block, NAME));
        // POSIX ustar ("ustar\0") splits long names into prefix and name; GNU ("ustar ") uses
        // that space for other fields and writes long names as 'L' entries instead.
        if (h.block[MAGIC.offset + 5] == 0) {
            if (const std::string_view prefix = text(h.block, PREFIX); !prefix.empty())
                h.raw_name = std::string(prefix) + "/" + h.raw_name;
        }
        if (m_long_name && h.type != 'L' && h.type != 'x' && h.type != 'g')
            h.raw_name = *std::exchange(m_long_name, {});
        h.where = h.raw_name.empty() ? h.at : entry_label(h.raw_name);
        return {};
    }

    /// Step 2: by type: regular files are kept, directories and global headers skipped, long
    /// names remembered for the next header, links and devices refused.
    Imported<Step> by_type(const TarHeader& h) {
        switch (h.type) {
            case '0':
            case '\0':
            case '7':
                return Step::Keep;
            case '5':
            case 'g':
                return Step::Skip;
            case 'L':
            case 'x':
                return long_name(h);
            case '1':
            case '2':
            case 'K':
                return m_sink.unsupported(
                    h.where,
                    std::string(h.type == '1' ? "is a hard link" : "is a symbolic link") +
                        (h.type == 'K' ? std::string()
                                       : " to '" + printable_name(text(h.block, LINKNAME)) + "'") +
                        ": links are refused; archive the file itself (tar -h)");
            case '3':
            case '4':
            case '6':
                return m_sink.unsupported(
                    h.where, h.type == '6' ? "is a FIFO: refused" : "is a device file: refused");
            default:
                return m_sink.unsupported(
                    h.where, "has entry type '" + printable_name(std::string_view(&h.type, 1)) +
                                 "': only regular files and directories "
                                 "are read");
        }
    }

    /// A GNU long name ('L') or a pax extended header ('x'): the next entry's name.
    Imported<Step> long_name(const TarHeader& h) {
        const std::string_view data(reinterpret_cast<const char*>(h.data.data()), h.data.size());
        if (h.size > MAX_META_BYTES)
            return m_sink.invalid(h.at, "a long name or pax header of more than " +
                                            std::to_string(MAX_META_BYTES) + " bytes");
        if (h.type == 'L') {
            m_long_name = std::string(data.substr(0, data.find('\0')));
            return Step::Skip;
        }
        bool size_record = false;
        auto path = pax_path(data, size_record);
        if (!path) return m_sink.invalid(h.at, "a malformed pax extended header");
        if (size_record)
            return m_sink.unsupported(h.at, "a pax 'size' record (entries over 8 GiB) is not read");
        if (!path->empty()) m_long_name = std::move(*path);
        return Step::Skip;
    }

    /// Step 3: a regular file: its name normalised and unique, its size counted.
    Imported<void> keep(const TarHeader& h) {
        NormalName name = normalize_entry_name(h.raw_name);
        if (!name.refusal.empty()) return m_sink.invalid(h.where, name.refusal);
        if (!m_seen.insert(name.path).second)
            return m_sink.invalid(entry_label(name.path), "appears twice in the archive");
        m_total += h.size;
        if (m_total > m_limits.max_total_bytes)
            return m_sink.too_large(entry_label(name.path),
                                    "the archive's files add up to more than " +
                                        std::to_string(m_limits.max_total_bytes) + " bytes");
        m_entries.push_back({std::move(name.path), h.data, h.offset});
        return {};
    }

    std::span<const uint8_t> m_body;
    ErrorSink m_sink;
    const TarLimits& m_limits;
    std::vector<TarEntry> m_entries;
    std::set<std::string, std::less<>> m_seen;
    std::optional<std::string> m_long_name;  // GNU 'L' or pax "path", for the next header
    uint64_t m_offset = 0, m_headers = 0, m_total = 0;
};

}  // namespace

Imported<std::vector<TarEntry>> read_tar(std::span<const uint8_t> body, const std::string& archive,
                                         const TarLimits& limits) {
    return TarWalk(body, archive, limits).run();
}

}  // namespace strata::assets

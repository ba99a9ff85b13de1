#include "engine/image/npz.h"

#include <bit>
#include <limits>
#include <new>

#include <zlib.h>

#include "engine/core/utf8.h"

namespace strata {

namespace {

static_assert(std::endian::native == std::endian::little,
              "arrays are written as they lie in memory, which .npy's '<' dtypes require");

void put16(std::string& out, uint32_t v) {
    out.push_back(char(v & 0xFF));
    out.push_back(char((v >> 8) & 0xFF));
}

void put32(std::string& out, uint32_t v) {
    put16(out, v & 0xFFFF);
    put16(out, v >> 16);
}

/// 1980-01-01 00:00 in MS-DOS form: archives of the same arrays are the same bytes.
constexpr uint32_t DOS_TIME = 0;
constexpr uint32_t DOS_DATE = (0 << 9) | (1 << 5) | 1;
constexpr uint32_t ZIP_VERSION = 20;  // 2.0: what stored entries need

/// What the central directory repeats of each entry.
struct Entry {
    std::string name;
    uint32_t crc = 0;
    uint32_t size = 0;
    uint32_t offset = 0;
};

/// The fields a local header and a central-directory header share, from "version needed" to
/// the name's length.
void put_common(std::string& out, const Entry& e) {
    put16(out, ZIP_VERSION);
    put16(out, 0);  // flags
    put16(out, 0);  // method: stored
    put16(out, DOS_TIME);
    put16(out, DOS_DATE);
    put32(out, e.crc);
    put32(out, e.size);  // compressed
    put32(out, e.size);  // uncompressed
    put16(out, uint32_t(e.name.size()));
    put16(out, 0);  // extra field length
}

uint32_t crc_of(uint32_t crc, std::string_view bytes) {
    // zlib's crc32 takes a uInt length: feed it in chunks.
    constexpr std::size_t CHUNK = std::size_t(1) << 30;
    for (std::size_t i = 0; i < bytes.size(); i += CHUNK) {
        const std::size_t n = std::min(CHUNK, bytes.size() - i);
        crc = uint32_t(::crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + i), uInt(n)));
    }
    return crc;
}

}  // namespace

std::string npy_header(const NpyArray& a) {
    std::string dict = "{'descr': '" + a.descr + "', 'fortran_order': False, 'shape': (";
    // Python's tuple syntax: "(5,)" for one dimension, "(2, 3)" for more.
    for (std::size_t i = 0; i < a.shape.size(); ++i)
        dict += (i ? ", " : "") + std::to_string(a.shape[i]);
    dict += a.shape.size() == 1 ? ",), }" : "), }";
    // Magic (6), version (2), header length (2), then the dict padded with spaces and ended by
    // a newline so that the data starts 64-byte aligned.
    const std::size_t unpadded = 10 + dict.size() + 1;
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict.push_back('\n');
    std::string out("\x93NUMPY\x01\x00", 8);
    put16(out, uint32_t(dict.size()));
    return out + dict;
}

Result<std::string> encode_npz(const std::vector<NpyArray>& arrays) {
    constexpr uint64_t ZIP_MAX = std::numeric_limits<uint32_t>::max();
    uint64_t total = 22;
    for (const NpyArray& a : arrays) total += 2 * (46 + a.name.size() + 4) + 128 + a.bytes.size();
    if (total >= ZIP_MAX)
        return failure(ErrorCode::TooLarge,
                       "the arrays take " + std::to_string(total) +
                           " bytes, more than an .npz without ZIP64 holds (4 GiB): ask for fewer "
                           "AOVs or fewer pixels",
                       "width");
    std::string out;
    std::vector<Entry> entries;
    try {
        out.reserve(std::size_t(total));
        for (const NpyArray& a : arrays) {
            const std::string head = npy_header(a);
            Entry e{a.name + ".npy", 0, 0, uint32_t(out.size())};
            e.crc = crc_of(crc_of(0, head), a.bytes);
            e.size = uint32_t(head.size() + a.bytes.size());
            put32(out, 0x04034b50);
            put_common(out, e);
            out += e.name;
            out += head;
            out.append(a.bytes.data(), a.bytes.size());
            entries.push_back(std::move(e));
        }
        const uint32_t directory = uint32_t(out.size());
        for (const Entry& e : entries) {
            put32(out, 0x02014b50);
            put16(out, ZIP_VERSION);  // made by
            put_common(out, e);
            put16(out, 0);  // comment length
            put16(out, 0);  // disk
            put16(out, 0);  // internal attributes
            put32(out, 0);  // external attributes
            put32(out, e.offset);
            out += e.name;
        }
        const uint32_t directory_size = uint32_t(out.size()) - directory;
        put32(out, 0x06054b50);
        put16(out, 0);  // this disk
        put16(out, 0);  // the directory's disk
        put16(out, uint32_t(entries.size()));
        put16(out, uint32_t(entries.size()));
        put32(out, directory_size);
        put32(out, directory);
        put16(out, 0);  // comment length
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to encode the frame", "width");
    }
    return out;
}

std::string utf32_array(const std::vector<std::string>& texts, std::vector<uint32_t>& out) {
    std::vector<std::vector<uint32_t>> points(texts.size());
    std::size_t width = 1;
    for (std::size_t i = 0; i < texts.size(); ++i) {
        std::string_view s = texts[i];
        while (!s.empty()) {
            const std::size_t n = utf8_sequence_length(s);
            points[i].push_back(n ? utf8_code_point(s, n) : 0xFFFD);
            s.remove_prefix(n ? n : 1);
        }
        width = std::max(width, points[i].size());
    }
    out.assign(texts.size() * width, 0);
    for (std::size_t i = 0; i < texts.size(); ++i)
        std::copy(points[i].begin(), points[i].end(), out.begin() + i * width);
    return "<U" + std::to_string(width);
}

}  // namespace strata

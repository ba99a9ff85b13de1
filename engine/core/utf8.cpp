#include "engine/core/utf8.h"

namespace strata {

std::size_t utf8_sequence_length(std::string_view s) {
    const auto byte = [&](std::size_t i) { return static_cast<uint8_t>(s[i]); };
    const uint8_t b0 = byte(0);
    if (b0 < 0x80) return 1;
    std::size_t n = 0;
    uint8_t lo = 0x80, hi = 0xBF;  // range of the second byte (RFC 3629 table)
    if (b0 >= 0xC2 && b0 <= 0xDF) {
        n = 2;
    } else if (b0 >= 0xE0 && b0 <= 0xEF) {
        n = 3;
        if (b0 == 0xE0) lo = 0xA0;  // overlong
        if (b0 == 0xED) hi = 0x9F;  // surrogates
    } else if (b0 >= 0xF0 && b0 <= 0xF4) {
        n = 4;
        if (b0 == 0xF0) lo = 0x90;  // overlong
        if (b0 == 0xF4) hi = 0x8F;  // above U+10FFFF
    } else {
        return 0;
    }
    if (s.size() < n || byte(1) < lo || byte(1) > hi) return 0;
    for (std::size_t i = 2; i < n; ++i) {
        if (byte(i) < 0x80 || byte(i) > 0xBF) return 0;
    }
    return n;
}

uint32_t utf8_code_point(std::string_view s, std::size_t n) {
    const auto byte = [&](std::size_t i) { return uint32_t(static_cast<uint8_t>(s[i])); };
    if (n == 1) return byte(0);
    uint32_t cp = byte(0) & (0xFFu >> (n + 1));
    for (std::size_t i = 1; i < n; ++i) cp = (cp << 6) | (byte(i) & 0x3F);
    return cp;
}

bool is_valid_utf8(std::string_view text) {
    while (!text.empty()) {
        const std::size_t n = utf8_sequence_length(text);
        if (n == 0) return false;
        text.remove_prefix(n);
    }
    return true;
}

bool is_control_code_point(uint32_t cp) {
    return cp < 0x20 || cp == 0x7F || (cp >= 0x80 && cp <= 0x9F) || cp == 0x2028 || cp == 0x2029;
}

std::size_t utf8_length(std::string_view text) {
    std::size_t n = 0;
    for (unsigned char c : text) n += (c & 0xC0) != 0x80;
    return n;
}

namespace {

/// Bytes of printable ASCII at the start of `text`: the common case, checked a byte at a time
/// without decoding.
std::size_t printable_ascii_prefix(std::string_view text) {
    std::size_t i = 0;
    while (i < text.size() && static_cast<unsigned char>(text[i]) - 0x20u < 0x5Fu) ++i;
    return i;
}

}  // namespace

const char* id_problem(std::string_view id) {
    if (id.empty()) return "is empty";
    if (printable_ascii_prefix(id) == id.size())
        return id.size() > MAX_ID_CODE_POINTS ? "is longer than 256 characters" : nullptr;
    if (const char* why = text_problem(id, 4 * MAX_ID_CODE_POINTS)) return why;
    if (utf8_length(id) > MAX_ID_CODE_POINTS) return "is longer than 256 characters";
    return nullptr;
}

const char* text_problem(std::string_view text, std::size_t max_bytes) {
    if (text.size() > max_bytes) return "is too long";
    text.remove_prefix(printable_ascii_prefix(text));
    while (!text.empty()) {
        const std::size_t n = utf8_sequence_length(text);
        if (n == 0) return "is not valid UTF-8";
        if (is_control_code_point(utf8_code_point(text, n))) return "holds a control character";
        text.remove_prefix(n);
    }
    return nullptr;
}

}  // namespace strata

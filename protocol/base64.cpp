#include "protocol/base64.h"

#include <array>
#include <cstdint>

namespace strata::protocol {

namespace {

constexpr char ALPHABET[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
constexpr uint8_t INVALID = 0xFF;

constexpr std::array<uint8_t, 256> make_table() {
    std::array<uint8_t, 256> t{};
    for (auto& v : t) v = INVALID;
    for (uint8_t i = 0; i < 64; ++i) t[static_cast<uint8_t>(ALPHABET[i])] = i;
    return t;
}
constexpr std::array<uint8_t, 256> TABLE = make_table();

}  // namespace

std::optional<std::string> decode_base64(std::string_view text, std::size_t* bad_at) {
    auto bad = [&](std::size_t at) -> std::optional<std::string> {
        if (bad_at) *bad_at = at;
        return std::nullopt;
    };
    if (text.size() % 4 != 0) return bad(text.size());
    std::size_t padding = 0;
    if (!text.empty() && text.back() == '=') padding = text[text.size() - 2] == '=' ? 2 : 1;
    std::string out;
    out.resize(text.size() / 4 * 3 - padding);
    const auto* in = reinterpret_cast<const uint8_t*>(text.data());
    const std::size_t full = padding ? text.size() - 4 : text.size();
    std::size_t o = 0;
    // Step: full quads, the hot loop (validity is OR-ed and checked once per quad).
    for (std::size_t i = 0; i < full; i += 4) {
        const uint8_t a = TABLE[in[i]], b = TABLE[in[i + 1]], c = TABLE[in[i + 2]],
                      d = TABLE[in[i + 3]];
        if ((a | b | c | d) & 0xC0) {
            for (std::size_t k = i;; ++k) {
                if (TABLE[in[k]] == INVALID) return bad(k);
            }
        }
        const uint32_t v = uint32_t(a) << 18 | uint32_t(b) << 12 | uint32_t(c) << 6 | d;
        out[o++] = static_cast<char>(v >> 16);
        out[o++] = static_cast<char>(v >> 8);
        out[o++] = static_cast<char>(v);
    }
    // Step: the padded last quad.
    if (padding) {
        const std::size_t i = full;
        const std::size_t data_chars = 4 - padding;
        uint32_t v = 0;
        for (std::size_t k = 0; k < 4; ++k) {
            uint8_t x = 0;
            if (k < data_chars) {
                x = TABLE[in[i + k]];
                if (x == INVALID) return bad(i + k);
            } else if (in[i + k] != '=') {
                return bad(i + k);
            }
            v |= uint32_t(x) << (18 - 6 * k);
        }
        out[o++] = static_cast<char>(v >> 16);
        if (padding == 1) out[o++] = static_cast<char>(v >> 8);
    }
    return out;
}

std::string encode_base64(std::string_view bytes) {
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    const auto* in = reinterpret_cast<const uint8_t*>(bytes.data());
    std::size_t i = 0;
    for (; i + 3 <= bytes.size(); i += 3) {
        const uint32_t v = uint32_t(in[i]) << 16 | uint32_t(in[i + 1]) << 8 | in[i + 2];
        for (int k = 0; k < 4; ++k) out.push_back(ALPHABET[(v >> (18 - 6 * k)) & 63]);
    }
    const std::size_t rest = bytes.size() - i;
    if (rest) {
        uint32_t v = uint32_t(in[i]) << 16;
        if (rest == 2) v |= uint32_t(in[i + 1]) << 8;
        out.push_back(ALPHABET[(v >> 18) & 63]);
        out.push_back(ALPHABET[(v >> 12) & 63]);
        out.push_back(rest == 2 ? ALPHABET[(v >> 6) & 63] : '=');
        out.push_back('=');
    }
    return out;
}

}  // namespace strata::protocol

#include "protocol/safe_text.h"

#include <algorithm>
#include <cstdint>

#include "engine/core/utf8.h"

namespace strata::protocol {

namespace {

void append_hex_escape(std::string& out, uint8_t b) {
    static constexpr char HEX[] = "0123456789abcdef";
    out += "\\x";
    out += HEX[b >> 4];
    out += HEX[b & 15];
}

}  // namespace

std::string to_valid_utf8(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    while (!text.empty()) {
        const std::size_t n = utf8_sequence_length(text);
        if (n == 0) {
            out += "\xEF\xBF\xBD";
            text.remove_prefix(1);
        } else {
            out.append(text.substr(0, n));
            text.remove_prefix(n);
        }
    }
    return out;
}

std::string escape_for_log(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    while (!text.empty()) {
        const std::size_t n = utf8_sequence_length(text);
        const uint32_t cp = n ? utf8_code_point(text, n) : 0;
        const bool control = n == 0 || is_control_code_point(cp);
        if (control) {
            for (std::size_t i = 0; i < std::max<std::size_t>(n, 1); ++i)
                append_hex_escape(out, static_cast<uint8_t>(text[i]));
            text.remove_prefix(std::max<std::size_t>(n, 1));
            continue;
        }
        if (cp == '\\') out += '\\';
        out.append(text.substr(0, n));
        text.remove_prefix(n);
    }
    return out;
}

std::string dump_json(const Json& j) {
    return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace strata::protocol

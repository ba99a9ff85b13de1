#pragma once
// Strict base64 (RFC 4648 section 4, standard alphabet, '=' padding, no whitespace).

#include <optional>
#include <string>
#include <string_view>

namespace strata::protocol {

/// Decoded bytes, or nullopt with `bad_at` set to the offset of the first offending character
/// (or to the length when it is not a multiple of 4).
std::optional<std::string> decode_base64(std::string_view text, std::size_t* bad_at = nullptr);

/// Encodes bytes (for tests, tools and clients).
std::string encode_base64(std::string_view bytes);

}  // namespace strata::protocol

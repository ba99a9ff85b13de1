#pragma once
// Parses a request body into an nlohmann DOM with a strict hand-written reader (RFC 8259: UTF-8,
// no comments, no trailing data; duplicate keys refused), enforcing nesting and array limits as
// it goes. nlohmann's own lexer copies every character of a number into a token buffer and calls
// strtod; this reader converts numbers in place with std::from_chars, several times faster on the
// 3M-number arrays of a 1M-vertex mesh (see tests/bench/protocol_bench.cpp).
//
// Long arrays whose elements are all numbers are not expanded into one DOM node per number: they
// are packed into a single binary node holding doubles (a node JSON text can never produce).
// Readers in json_fields.h accept both forms transparently.

#include <cstddef>
#include <string_view>

#include <nlohmann/json.hpp>

#include "protocol/problem.h"

namespace strata::protocol {

using Json = nlohmann::json;

/// Limits applied while parsing untrusted JSON.
struct JsonLimits {
    std::size_t max_depth = 64;                 ///< nested arrays and objects
    std::size_t max_array_elements = 1u << 26;  ///< elements in any one array
    /// Values in the whole document, packed numbers not counted: what bounds the DOM's memory
    /// (about 100 bytes a value) whatever the body's shape.
    std::size_t max_values = 1u << 20;
};

/// Arrays of at least this many numbers are packed.
constexpr std::size_t PACK_THRESHOLD = 64;
/// Binary subtype that marks a packed numeric array.
constexpr std::uint64_t PACKED_NUMBERS_SUBTYPE = 0x5354;  // "ST"

/// Parses `text` as one strict JSON value (no comments, no trailing data, no duplicate keys).
Parsed<Json> parse_json(std::string_view text, const JsonLimits& limits = {});

/// True when `v` is a packed numeric array.
bool is_packed_numbers(const Json& v);
/// Number of elements of a packed numeric array (`v` must be one).
std::size_t packed_size(const Json& v);
/// Element `i` of a packed numeric array (`v` must be one, `i` < packed_size(v)).
double packed_value(const Json& v, std::size_t i);

}  // namespace strata::protocol

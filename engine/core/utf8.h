#pragma once
// UTF-8 as RFC 3629 defines it, and the rule every piece of client text in the scene keeps (ids
// and display names): well-formed, no control characters, bounded. The scene checks it for
// every way in (JSON, snapshots, the journal, replicated records), so no reader of the scene
// ever meets bytes it cannot write out.

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace strata {

/// Length of the well-formed UTF-8 sequence at the start of `s` (not empty), or 0 when there
/// is none (no overlong forms, no surrogates, nothing above U+10FFFF).
std::size_t utf8_sequence_length(std::string_view s);

/// The code point of the well-formed sequence of `n` bytes at the start of `s`.
uint32_t utf8_code_point(std::string_view s, std::size_t n);

/// True when `text` is well-formed UTF-8.
bool is_valid_utf8(std::string_view text);

/// C0 and C1 controls, DEL and the line and paragraph separators: characters that would let
/// text forge a line in a log or a header.
bool is_control_code_point(uint32_t cp);

/// Code points in well-formed UTF-8 text.
std::size_t utf8_length(std::string_view text);

/// Longest id, in code points.
constexpr std::size_t MAX_ID_CODE_POINTS = 256;

/// Why `id` cannot name an object ("is empty", "is longer than 256 characters", "is not valid
/// UTF-8", "holds a control character"), or nullptr when it can. Ids end up in URLs, logs,
/// headers and JSON; this rule holds for every way an object comes in.
const char* id_problem(std::string_view id);

/// Why `text` is not acceptable scene text of at most `max_bytes` bytes ("is not valid UTF-8",
/// "holds a control character", "is longer than N bytes"), or nullptr when it is.
const char* text_problem(std::string_view text, std::size_t max_bytes);

}  // namespace strata

#pragma once
// Text that came from the network is untrusted bytes: it may be invalid UTF-8 (which
// nlohmann::json refuses to serialise, throwing) or hold CR/LF (which would let a client forge
// log lines). Everything a request contributes to a JSON document or a log line goes through one
// of these first.

#include <string>
#include <string_view>

#include "engine/core/utf8.h"
#include "protocol/json_document.h"

namespace strata::protocol {

using strata::is_valid_utf8;

/// `text` with each byte of an invalid UTF-8 sequence replaced by U+FFFD.
std::string to_valid_utf8(std::string_view text);

/// `text` made safe for a one-line log record: printable ASCII and well-formed non-ASCII UTF-8
/// are kept; control characters (CR and LF included), DEL, C1 controls, U+2028/U+2029 and bytes of
/// invalid sequences become `\xNN`; a backslash becomes `\\`, so an escape is never ambiguous.
std::string escape_for_log(std::string_view text);

/// Serialises `j`; strings that are not valid UTF-8 have the bad bytes replaced by U+FFFD instead
/// of throwing (nlohmann's default), so no request text can turn an answer into an exception.
std::string dump_json(const Json& j);

}  // namespace strata::protocol

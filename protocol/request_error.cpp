#include "protocol/request_error.h"

namespace strata::protocol {

void fail_schema(std::string pointer, std::string message) {
    RequestError e;
    e.kind = RequestErrorKind::Schema;
    e.message = std::move(message);
    e.pointer = std::move(pointer);
    throw RequestFailure(std::move(e));
}

void fail_value(std::string pointer, std::string message, ErrorCode code) {
    RequestError e;
    e.kind = RequestErrorKind::Value;
    e.code = code;
    e.message = std::move(message);
    e.pointer = std::move(pointer);
    throw RequestFailure(std::move(e));
}

std::string escape_pointer_token(std::string_view token) {
    std::string out;
    out.reserve(token.size());
    for (char c : token) {
        if (c == '~') {
            out += "~0";
        } else if (c == '/') {
            out += "~1";
        } else {
            out += c;
        }
    }
    return out;
}

}  // namespace strata::protocol

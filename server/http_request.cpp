#include "server/http_request.h"

namespace strata::server {

const std::string* HttpRequest::header(std::string_view name) const {
    return find_header(headers, name);
}

std::optional<std::string> HttpRequest::header_value(std::string_view name) const {
    const std::string* value = header(name);
    return value ? std::optional<std::string>(*value) : std::nullopt;
}

std::size_t HttpRequest::held_bytes() const {
    std::size_t n = method.size() + path.size() + body.size();
    for (const auto& [name, value] : query) n += name.size() + value.size();
    for (const HeaderField& f : headers) n += f.name.size() + f.value.size();
    return n;
}

}  // namespace strata::server

#include "server/http_request.h"

#include <charconv>

namespace strata::server {

const std::string* HttpRequest::header(std::string_view name) const {
    return find_header(headers, name);
}

std::optional<std::string> HttpRequest::header_value(std::string_view name) const {
    const std::string* value = header(name);
    return value ? std::optional<std::string>(*value) : std::nullopt;
}

std::optional<HttpRequest::MinVersion> HttpRequest::min_version() const {
    MinVersion asked;
    if (auto it = query.find("min_version"); it != query.end())
        asked.text = it->second;
    else if (const std::string* h = header("X-Strata-Min-Version"))
        asked.text = *h;
    else
        return std::nullopt;
    const char* end = asked.text.data() + asked.text.size();
    const auto [stop, ec] = std::from_chars(asked.text.data(), end, asked.version);
    asked.valid = !asked.text.empty() && ec == std::errc() && stop == end;
    return asked;
}

std::size_t HttpRequest::held_bytes() const {
    std::size_t n = method.size() + path.size() + body.size();
    for (const auto& [name, value] : query) n += name.size() + value.size();
    for (const HeaderField& f : headers) n += f.name.size() + f.value.size();
    return n;
}

}  // namespace strata::server

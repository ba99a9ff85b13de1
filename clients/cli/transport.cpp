#include "clients/cli/transport.h"

#include <cctype>
#include <charconv>

#include <nlohmann/json.hpp>

namespace strata::cli {

namespace {

Reply single_scene(const Transport& t) {
    Reply r;
    r.error = t.describe() + " holds one scene: named scenes need a server";
    return r;
}

}  // namespace

Reply Transport::scenes() {
    return single_scene(*this);
}

Reply Transport::put_scene(const std::string&, const std::string&) {
    return single_scene(*this);
}

Reply Transport::delete_scene(const std::string&) {
    return single_scene(*this);
}

namespace {

bool equal_ignoring_case(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(a[i])) !=
            std::tolower(static_cast<unsigned char>(b[i])))
            return false;
    return true;
}

}  // namespace

std::string Reply::header(std::string_view name) const {
    for (const auto& [key, value] : headers)
        if (equal_ignoring_case(key, name)) return value;
    return {};
}

std::optional<uint64_t> etag_version(const Reply& reply) {
    std::string tag = reply.header("ETag");
    if (tag.size() >= 2 && tag.front() == '"' && tag.back() == '"')
        tag = tag.substr(1, tag.size() - 2);
    uint64_t v = 0;
    const auto [end, ec] = std::from_chars(tag.data(), tag.data() + tag.size(), v);
    if (tag.empty() || ec != std::errc() || end != tag.data() + tag.size()) return std::nullopt;
    return v;
}

std::string describe_failure(const Reply& reply) {
    if (reply.status == 0) return reply.error.empty() ? "no answer" : reply.error;
    const auto doc = nlohmann::json::parse(reply.body, nullptr, false);
    const bool problem =
        reply.content_type.rfind("application/problem+json", 0) == 0 && doc.is_object();
    if (!problem) {
        std::string body = reply.body.substr(0, 200);
        for (char& c : body)
            if (static_cast<unsigned char>(c) < 0x20 && c != '\n') c = ' ';
        return "HTTP " + std::to_string(reply.status) + (body.empty() ? "" : ": " + body);
    }
    auto text = [&](const char* key) {
        return doc.contains(key) && doc[key].is_string() ? doc[key].get<std::string>() : "";
    };
    std::string out = std::to_string(doc.value("status", reply.status)) + " " + text("title");
    if (!text("detail").empty()) out += "\n  detail:     " + text("detail");
    if (doc.contains("edit_index") && doc["edit_index"].is_number())
        out += "\n  edit index: " + doc["edit_index"].dump();
    if (doc.contains("pointer"))
        out +=
            "\n  pointer:    " + (text("pointer").empty() ? "(the whole body)" : text("pointer"));
    if (!text("type").empty()) out += "\n  type:       " + text("type");
    return out;
}

std::string percent_encode(std::string_view text) {
    static constexpr char HEX[] = "0123456789ABCDEF";
    std::string out;
    out.reserve(text.size());
    for (const char ch : text) {
        const auto c = static_cast<unsigned char>(ch);
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
            c == '-' || c == '.' || c == '_' || c == '~') {
            out += ch;
        } else {
            out += '%';
            out += HEX[c >> 4];
            out += HEX[c & 15];
        }
    }
    return out;
}

}  // namespace strata::cli

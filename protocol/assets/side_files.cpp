#include "protocol/assets/side_files.h"

#include <cctype>
#include <vector>

namespace strata::assets {

std::optional<std::string> normalize_reference(std::string_view reference) {
    if (reference.find('\0') != std::string_view::npos) return std::nullopt;
    std::string path(reference);
    for (char& c : path)
        if (c == '\\') c = '/';
    if (!path.empty() && path.front() == '/') return std::nullopt;
    if (path.size() >= 2 && path[1] == ':' && std::isalpha(static_cast<unsigned char>(path[0])))
        return std::nullopt;
    std::vector<std::string_view> parts;
    std::string_view rest = path;
    while (!rest.empty()) {
        const std::size_t slash = rest.find('/');
        const std::string_view part = rest.substr(0, slash);
        rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
        if (part.empty() || part == ".") continue;
        if (part == ".." && !parts.empty() && parts.back() != "..")
            parts.pop_back();
        else
            parts.push_back(part);
    }
    std::string out;
    for (std::string_view p : parts) {
        if (!out.empty()) out += '/';
        out += p;
    }
    return out;
}

const std::string* find_side_file(const SideFiles& files, std::string_view reference) {
    if (files.empty()) return nullptr;
    const auto key = normalize_reference(reference);
    if (!key || key->empty()) return nullptr;
    const auto it = files.find(*key);
    return it == files.end() ? nullptr : &it->second;
}

}  // namespace strata::assets

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
    if (const auto key = normalize_reference(reference); key) {
        if (key->empty()) return nullptr;
        if (const auto it = files.find(*key); it != files.end()) return &it->second;
        // A reference above the model's folder names nothing else.
        if (key->starts_with("..")) return nullptr;
    }
    // Step: the file's name alone, at the top of the upload.
    const std::size_t cut = reference.find_last_of("/\\");
    const std::string_view name = cut == std::string_view::npos ? reference : reference.substr(cut + 1);
    if (name.empty() || name == "." || name == ".." || name.find('\0') != std::string_view::npos)
        return nullptr;
    const auto it = files.find(name);
    return it == files.end() ? nullptr : &it->second;
}

}  // namespace strata::assets

#pragma once
// The render format a file name asks for, for `strata render -o` and a script's "out".

#include <cctype>
#include <string_view>

namespace strata::cli {

/// "png", "exr" or "npz" from the name's extension (any case); nullptr for another extension.
inline const char* format_of_file_name(std::string_view name) {
    for (const char* format : {"png", "exr", "npz"}) {
        const std::string_view ext(format);
        if (name.size() <= ext.size() || name[name.size() - ext.size() - 1] != '.') continue;
        bool same = true;
        for (std::size_t i = 0; i < ext.size(); ++i)
            same = same && std::tolower(static_cast<unsigned char>(
                               name[name.size() - ext.size() + i])) == ext[i];
        if (same) return format;
    }
    return nullptr;
}

}  // namespace strata::cli

#pragma once
// The viewer's files (clients/web), compiled into the server by cmake/embed_files.cmake.

#include <string>
#include <string_view>
#include <vector>

namespace strata::server {

struct WebAsset {
    std::string path;        ///< relative to clients/web, '/'-separated ("index.html")
    std::string_view bytes;  ///< static storage
};

/// Every file of the viewer, sorted by path.
const std::vector<WebAsset>& web_assets();

}  // namespace strata::server

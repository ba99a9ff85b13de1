#pragma once
// The demo scene's model files (protocol/demo/*.obj), compiled in by cmake/embed_files.cmake.

#include <string>
#include <string_view>
#include <vector>

namespace strata::demo {

struct DemoFile {
    std::string path;        ///< relative to protocol/demo ("spot.obj")
    std::string_view bytes;  ///< static storage
};

/// Every model file of the demo scene, sorted by path.
const std::vector<DemoFile>& demo_files();

}  // namespace strata::demo

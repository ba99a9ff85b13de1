#pragma once
// Test helpers for documents with generated parts: a table between
// `<!-- BEGIN GENERATED name: ... -->` and `<!-- END GENERATED name -->` is rewritten from the
// table it documents when STRATA_UPDATE_DOCS=1, and compared otherwise.

#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace strata::test {

inline std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    EXPECT_TRUE(in.good()) << "cannot read " << path;
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

/// True when the run should rewrite generated parts (STRATA_UPDATE_DOCS=1).
inline bool updating_docs() {
    const char* update = std::getenv("STRATA_UPDATE_DOCS");
    return update && std::string(update) == "1";
}

inline void write_text(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    ASSERT_TRUE(out.good()) << "cannot write " << path;
}

/// `text` with the lines between the markers of region `name` replaced by `content`; nullopt
/// when a marker is missing.
inline std::optional<std::string> with_region(const std::string& text, const std::string& name,
                                              const std::string& content) {
    const std::size_t begin = text.find("<!-- BEGIN GENERATED " + name + ":");
    const std::size_t end = text.find("<!-- END GENERATED " + name + " -->");
    if (begin == std::string::npos || end == std::string::npos || end < begin) return std::nullopt;
    const std::size_t body = text.find('\n', begin);
    if (body == std::string::npos || body > end) return std::nullopt;
    return text.substr(0, body + 1) + content + text.substr(end);
}

}  // namespace strata::test

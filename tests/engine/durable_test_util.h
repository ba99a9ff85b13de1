#pragma once
// A temporary data directory and hit-buffer capture for the durability tests.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "tests/engine/bulk_singles.h"
#include "engine/engine.h"

namespace strata::test {

/// A batch in the journal's and snapshots' binary form.
inline std::string encoded(const EditBatch& b) {
    std::string out;
    durable::encode_batch(b, out);
    return out;
}

/// A scene's objects and fields without slots, handles or child order: its rebuilding batch, one
/// encoded edit per object (bulk adds as their single edits), sorted. Two scenes with equal states
/// hold the same objects.
inline std::vector<std::string> state_of(const Scene& s) {
    std::vector<std::string> out;
    for (Edit& e : s.to_batch().edits) {
        if (const auto* bulk = std::get_if<AddInstances>(&e)) {
            for (Edit& one : singles(*bulk)) out.push_back(encoded(EditBatch{{std::move(one)}}));
        } else {
            out.push_back(encoded(EditBatch{{std::move(e)}}));
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}
inline std::vector<std::string> state_of(const Engine& e) {
    return e.read([](const Scene& s) { return state_of(s); });
}

/// A fresh directory under $TMPDIR, removed with everything in it at the end of the test.
class TempDir {
public:
    TempDir() {
        std::string pattern = (std::filesystem::temp_directory_path() / "strata-durable-XXXXXX");
        if (!::mkdtemp(pattern.data())) ADD_FAILURE() << "mkdtemp failed";
        m_path = pattern;
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(m_path, ec);
    }
    const std::string& path() const { return m_path; }
    std::string file(const std::string& name) const { return m_path + "/" + name; }

private:
    std::string m_path;
};

/// One frame of primary hits with instance slots turned into client ids.
struct Hits {
    std::vector<std::string> instance;
    std::vector<uint32_t> primitive;
    std::vector<float> depth;

    friend bool operator==(const Hits& a, const Hits& b) {
        if (a.instance != b.instance || a.primitive != b.primitive) return false;
        for (std::size_t i = 0; i < a.depth.size(); ++i) {
            if (std::isinf(a.depth[i]) && std::isinf(b.depth[i])) continue;
            // Same triangle, same ray: only a BVH built in another order may round differently.
            if (std::abs(a.depth[i] - b.depth[i]) > 1e-5f * std::abs(a.depth[i])) return false;
        }
        return a.depth.size() == b.depth.size();
    }
};

inline Hits hits(Engine& engine, uint32_t width = 64, uint32_t height = 48) {
    PrimarySettings settings;
    settings.width = width;
    settings.height = height;
    auto frame = engine.render_primary(settings);
    EXPECT_TRUE(frame.has_value()) << (frame ? "" : frame.error().describe());
    Hits h;
    if (!frame) return h;
    const FrameBuffers& b = frame->buffers;
    h.primitive = b.primitive_id;
    h.depth = b.depth;
    h.instance = engine.read([&](const Scene& s) {
        std::vector<std::string> out;
        for (uint32_t slot : b.instance_id)
            out.push_back(slot == INVALID_ID ? "" : s.instances().at_slot(slot).id);
        return out;
    });
    return h;
}

inline uint64_t version_of(const Engine& engine) {
    return engine.read([](const Scene& s) { return s.version(); });
}

}  // namespace strata::test

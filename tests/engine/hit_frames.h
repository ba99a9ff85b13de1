#pragma once
// Primary hits of one launch (distance, client instance id, primitive per pixel) and their
// comparison, for differential tests.

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/engine.h"

namespace strata::test {

constexpr float RELATIVE_TOLERANCE = 1e-4f;

struct HitFrame {
    FrameBuffers hits;
    std::vector<std::string> instance_ids;  ///< per pixel, "" for a miss
};

inline HitFrame render(Engine& engine, uint32_t ray_mask, RebuildReport* report = nullptr,
                       uint32_t width = 64, uint32_t height = 48) {
    PrimarySettings settings;
    settings.width = width;
    settings.height = height;
    settings.ray_mask = ray_mask;
    auto result = engine.render_primary(settings);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().describe());
    HitFrame f;
    if (!result.has_value()) return f;
    if (report) *report = result.value().info.report;
    f.hits = std::move(result.value().buffers);
    f.instance_ids = engine.read([&](const Scene& s) {
        std::vector<std::string> out;
        for (uint32_t slot : f.hits.instance_id) {
            out.push_back(slot == INVALID_ID ? "" : s.instances().at_slot(slot).id);
        }
        return out;
    });
    return f;
}

/// Differences between two frames, described pixel by pixel (empty when they agree).
inline std::string compare(const HitFrame& incremental, const HitFrame& scratch) {
    std::ostringstream out;
    int reported = 0;
    for (std::size_t p = 0; p < incremental.instance_ids.size(); ++p) {
        const float a = incremental.hits.depth[p], b = scratch.hits.depth[p];
        const bool same_hit = incremental.instance_ids[p] == scratch.instance_ids[p] &&
                              incremental.hits.primitive_id[p] == scratch.hits.primitive_id[p];
        const bool same_distance =
            (std::isinf(a) && std::isinf(b)) ||
            std::abs(a - b) <= RELATIVE_TOLERANCE * std::max(std::abs(a), std::abs(b));
        if (same_hit && same_distance) continue;
        if (reported++ < 5) {
            out << "  pixel (" << p % incremental.hits.width << ", " << p / incremental.hits.width
                << "): incremental " << incremental.instance_ids[p] << "/"
                << incremental.hits.primitive_id[p] << " at " << a << ", from scratch "
                << scratch.instance_ids[p] << "/" << scratch.hits.primitive_id[p] << " at " << b
                << "\n";
        }
    }
    if (reported > 5) out << "  ... " << reported - 5 << " more pixels\n";
    return out.str();
}

}  // namespace strata::test

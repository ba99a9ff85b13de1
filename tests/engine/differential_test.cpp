// The differential test: after any random sequence of edits, the incrementally maintained
// acceleration graph must give the same primary hits (instance, primitive, distance) as an
// engine that builds the same scene state from scratch.

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

constexpr int SEQUENCES = 200;
constexpr int BATCHES_PER_SEQUENCE = 12;
constexpr uint32_t WIDTH = 64;
constexpr uint32_t HEIGHT = 48;
constexpr float RELATIVE_TOLERANCE = 1e-4f;

struct HitFrame {
    FrameBuffers hits;
    std::vector<std::string> instance_ids;  ///< per pixel, "" for a miss
};

HitFrame render(Engine& engine, uint32_t ray_mask) {
    PrimarySettings settings;
    settings.width = WIDTH;
    settings.height = HEIGHT;
    settings.ray_mask = ray_mask;
    auto result = engine.render_primary(settings);
    EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().describe());
    HitFrame f;
    if (!result.has_value()) return f;
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
std::string compare(const HitFrame& incremental, const HitFrame& scratch) {
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
            out << "  pixel (" << p % WIDTH << ", " << p / WIDTH << "): incremental "
                << incremental.instance_ids[p] << "/" << incremental.hits.primitive_id[p] << " at "
                << a << ", from scratch " << scratch.instance_ids[p] << "/"
                << scratch.hits.primitive_id[p] << " at " << b << "\n";
        }
    }
    if (reported > 5) out << "  ... " << reported - 5 << " more pixels\n";
    return out.str();
}

TEST(Differential, IncrementalCommitsMatchARebuildFromScratch) {
    int commits = 0, hit_pixels = 0;
    for (int seq = 0; seq < SEQUENCES; ++seq) {
        test::RandomEdits edits(0x5EED0000u + uint64_t(seq));
        auto engine = test::make_engine();
        for (int batch = 0; batch < BATCHES_PER_SEQUENCE; ++batch) {
            auto applied =
                engine->apply(batch == 0 ? edits.initial_batch(3, 15) : edits.next_batch(6));
            ASSERT_TRUE(applied.has_value())
                << "sequence " << seq << " batch " << batch << ": " << applied.error().describe();
            // Sometimes let several batches pile up before the next launch.
            if (batch + 1 < BATCHES_PER_SEQUENCE && (seq + batch) % 3 == 0) continue;
            if (batch % 2)
                test::commit_ok(*engine);  // an explicit commit, then the launch's no-op one

            const uint32_t mask = edits.ray_mask();
            const HitFrame incremental = render(*engine, mask);
            auto scratch_engine = test::make_engine();
            ASSERT_TRUE(
                scratch_engine->apply(engine->read([](const Scene& s) { return s.to_batch(); }))
                    .has_value());
            const HitFrame scratch = render(*scratch_engine, mask);
            const std::string diff = compare(incremental, scratch);
            ASSERT_TRUE(diff.empty()) << "sequence " << seq << " batch " << batch << " differs:\n"
                                      << diff;
            ++commits;
            for (const auto& id : incremental.instance_ids) hit_pixels += !id.empty();
        }
    }
    // Guard against a vacuous pass: many launches, and images that actually show geometry.
    const double coverage = double(hit_pixels) / (double(commits) * WIDTH * HEIGHT);
    ::testing::Test::RecordProperty("launches", commits);
    ::testing::Test::RecordProperty("hit_coverage_percent", int(coverage * 100));
    EXPECT_GT(commits, SEQUENCES * 6);
    EXPECT_GT(coverage, 0.10) << commits << " launches";
}

}  // namespace
}  // namespace strata

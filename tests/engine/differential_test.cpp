// The differential test: after any random sequence of edits, the incrementally maintained
// acceleration graph must give the same primary hits (instance, primitive, distance) as an
// engine that builds the same scene state from scratch.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/many_instances.h"
#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::compare;
using test::HitFrame;
using test::render;

constexpr int SEQUENCES = 200;
constexpr int BATCHES_PER_SEQUENCE = 12;
constexpr uint32_t WIDTH = 64;
constexpr uint32_t HEIGHT = 48;

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

// Large scenes: the incremental TLAS (dynamic tier, stale static copies, background merges and
// their swaps, the synchronous fallback) against a fresh build with the embree strategy.

constexpr int MANY = 3000;
constexpr uint32_t BIG_WIDTH = 96;
constexpr uint32_t BIG_HEIGHT = 64;

EngineConfig tlas_config(TlasKind kind, double max_dynamic_fraction, bool merges) {
    EngineConfig c;
    c.accel.tlas = kind;
    c.accel.tlas_policy.min_instances = 256;
    c.accel.tlas_policy.max_dynamic_fraction = max_dynamic_fraction;
    c.accel.tlas_policy.background_merge = merges;
    return c;
}

std::unique_ptr<Engine> make_engine_with(const EngineConfig& config) {
    auto engine = Engine::create(config);
    EXPECT_TRUE(engine.has_value());
    return std::move(engine.value());
}

/// What the checks of one run went through.
struct TierCoverage {
    int launches = 0;
    int during_merge = 0;  ///< launches that traced while a merge was building
    int after_swap = 0;    ///< launches whose commit swapped a merge in
    int with_stale = 0;    ///< launches that traced past stale static copies
    int fallbacks = 0;     ///< commits that rebuilt the static tier for the policy
    uint64_t max_dynamic = 0;
};

void note(TierCoverage& c, const RebuildReport& r) {
    ++c.launches;
    c.during_merge += r.tlas.merge_running;
    c.after_swap += r.tlas.merge_swapped;
    c.with_stale += r.tlas.stale_copies > 0;
    c.fallbacks += std::string(r.tlas.static_rebuild) == "dynamic_tier_full";
    c.max_dynamic = std::max(c.max_dynamic, r.tlas.dynamic_instances);
}

/// Single rays (intersect1) from above the grid down to random points: client id, primitive and
/// distance of each hit, through one launch of `engine`.
std::vector<std::string> trace_singles(Engine& engine, uint64_t seed) {
    std::vector<std::string> out;
    std::vector<RayHit1> hits;
    auto launched = engine.launch([&](const FrameState&, const TlasStrategy& tlas,
                                      const RebuildReport&) {
        std::mt19937 rng{uint32_t(seed)};
        std::uniform_real_distribution<float> u(-40.0f, 40.0f);
        for (int i = 0; i < 300; ++i) {
            RayHit1 ray{};
            ray.org_x = u(rng);
            ray.org_y = 30.0f;
            ray.org_z = u(rng);
            ray.dir_x = u(rng) - ray.org_x;
            ray.dir_y = -30.0f;
            ray.dir_z = u(rng) - ray.org_z;
            ray.tfar = std::numeric_limits<float>::infinity();
            ray.mask = i % 5 == 0 ? 0x1u : 0xFFFFFFFFu;
            ray.geom_id = ray.inst_id = ray.prim_id = INVALID_ID;
            tlas.intersect1(ray, false);
            hits.push_back(ray);
        }
        return true;
    });
    EXPECT_TRUE(launched.has_value());
    engine.read([&](const Scene& s) {
        for (const RayHit1& h : hits) {
            std::ostringstream line;
            if (h.inst_id == INVALID_ID) {
                line << "miss";
            } else {
                line << s.instances().at_slot(h.inst_id).id << "/" << h.prim_id << " at "
                     << h.tfar;
            }
            out.push_back(line.str());
        }
        return 0;
    });
    return out;
}

/// Pixels whose shaded colour differs (sun shadows trace occluded16, bounces intersect16).
int shaded_differences(Engine& a, Engine& b) {
    RenderRequest request;
    request.width = 64;
    request.height = 48;
    auto fa = a.render_frame(request);
    auto fb = b.render_frame(request);
    EXPECT_TRUE(fa.has_value() && fb.has_value());
    if (!fa.has_value() || !fb.has_value()) return -1;
    int differ = 0;
    for (std::size_t p = 0; p < fa->buffers.color.size(); ++p) {
        const Vec3 d = fa->buffers.color[p] - fb->buffers.color[p];
        differ += std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}) > 1e-4f;
    }
    return differ;
}

/// Renders `engine` and a fresh embree-strategy build of its scene; they must agree.
void expect_matches_fresh_build(Engine& engine, uint32_t mask, const std::string& where,
                                TierCoverage& coverage, bool singles_and_shading) {
    RebuildReport report;
    const HitFrame incremental = render(engine, mask, &report, BIG_WIDTH, BIG_HEIGHT);
    note(coverage, report);
    auto scratch = make_engine_with(tlas_config(TlasKind::Embree, 0.1, false));
    ASSERT_TRUE(
        scratch->apply(engine.read([](const Scene& s) { return s.to_batch(); })).has_value());
    const HitFrame fresh = render(*scratch, mask, nullptr, BIG_WIDTH, BIG_HEIGHT);
    const std::string diff = compare(incremental, fresh);
    ASSERT_TRUE(diff.empty()) << where << " (" << report.summary() << ", dynamic "
                              << report.tlas.dynamic_instances << ", stale "
                              << report.tlas.stale_copies << ") differs:\n"
                              << diff;
    if (!singles_and_shading) return;
    const uint64_t seed = coverage.launches;
    EXPECT_EQ(trace_singles(engine, seed), trace_singles(*scratch, seed)) << where;
    EXPECT_LE(shaded_differences(engine, *scratch), 3) << where;
}

void run_many_instances(const EngineConfig& config, uint64_t seed, int rounds,
                        TierCoverage& coverage) {
    test::ManyInstances gen(seed);
    auto engine = make_engine_with(config);
    ASSERT_TRUE(engine->apply(gen.initial_batch(MANY)).has_value());
    expect_matches_fresh_build(*engine, 0xFFFFFFFFu, "first build", coverage, true);
    std::mt19937 rng{uint32_t(seed)};
    for (int round = 0; round < rounds; ++round) {
        const std::string where = "round " + std::to_string(round);
        const int edits = std::uniform_int_distribution<int>(1, 90)(rng);
        ASSERT_TRUE(engine->apply(gen.mixed_batch(edits)).has_value()) << where;
        if (round % 3 == 0) {  // several batches before one launch
            ASSERT_TRUE(engine->apply(gen.mixed_batch(edits / 2 + 1)).has_value()) << where;
        }
        if (round % 4 == 1) test::commit_ok(*engine);  // an explicit commit, then a no-op one
        // Usually right after the commit that started a merge: it is still building.
        expect_matches_fresh_build(*engine, gen.ray_mask(), where, coverage, round % 5 == 0);
        if (::testing::Test::HasFatalFailure()) return;
        if (round % 4 == 3) {
            // The merge finishes; the next launch's commit swaps it in.
            engine->wait_for_background();
            expect_matches_fresh_build(*engine, gen.ray_mask(), where + " after a swap", coverage,
                                       round % 8 == 7);
            if (::testing::Test::HasFatalFailure()) return;
            // Edits right after the swap, on instances that just left the dynamic tier.
            ASSERT_TRUE(engine->apply(gen.moves(20)).has_value());
            expect_matches_fresh_build(*engine, 0xFFFFFFFFu, where + " edits after a swap",
                                       coverage, false);
            if (::testing::Test::HasFatalFailure()) return;
        }
    }
}

TEST(Differential, ThousandsOfInstancesMatchAFreshBuildThroughMergesAndSwaps) {
    TierCoverage coverage;
    run_many_instances(tlas_config(TlasKind::Incremental, 0.25, true), 0x7140001u, 36, coverage);
    ::testing::Test::RecordProperty("launches", coverage.launches);
    ::testing::Test::RecordProperty("launches_during_merge", coverage.during_merge);
    ::testing::Test::RecordProperty("launches_after_swap", coverage.after_swap);
    // Guard against a vacuous pass: the tiers were really exercised.
    EXPECT_GT(coverage.max_dynamic, 50u);
    EXPECT_GE(coverage.with_stale, 20);
    EXPECT_GE(coverage.during_merge, 5);
    EXPECT_GE(coverage.after_swap, 5);
}

TEST(Differential, ThousandsOfInstancesMatchAFreshBuildThroughTheSynchronousFallback) {
    TierCoverage coverage;
    // No merges and a small dynamic tier: the fallback rebuilds the static tier now and then.
    run_many_instances(tlas_config(TlasKind::Incremental, 0.03, false), 0x7140002u, 24, coverage);
    EXPECT_GE(coverage.fallbacks, 2);
    EXPECT_GE(coverage.with_stale, 10);
    EXPECT_EQ(coverage.after_swap, 0);
}

}  // namespace
}  // namespace strata

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
    auto engine = test::create_engine(config);
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
    int arrays = 0;      ///< launches whose commit reported an instance-array static tier
    int geometries = 0;  ///< launches whose commit reported a static tier of geometries
    uint64_t max_dynamic = 0;
};

void note(TierCoverage& c, const RebuildReport& r) {
    ++c.launches;
    c.during_merge += r.tlas.merge_running;
    c.after_swap += r.tlas.merge_swapped;
    c.with_stale += r.tlas.stale_copies > 0;
    c.fallbacks += std::string(r.tlas.static_rebuild) == "dynamic_tier_full";
    c.arrays += r.tlas.static_array;
    c.geometries += r.tlas.static_instances > 0 && !r.tlas.static_array;
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
                        TierCoverage& coverage, bool motion_keys = true) {
    test::ManyInstances gen(seed);
    if (!motion_keys) gen.without_motion_keys();
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

// The same with the static tier an instance array (engine/accel/instance_array.h) against
// Embree's own instances: the same hits, edges and single rays included, through merges
// (which copy the array) and the fallback (which edits it in place). With motion keys in the
// scene the static tier is geometries (instance_array_test.cpp).
void run_instance_array(bool merges) {
    TierCoverage coverage;
    EngineConfig config = tlas_config(TlasKind::Incremental, merges ? 0.25 : 0.03, merges);
    config.accel.tlas_policy.array_min_instances = 0;
    // Without motion keys: a scene with some has instance geometries (instance_array_test.cpp).
    run_many_instances(config, merges ? 0x7140004u : 0x7140005u, 16, coverage, false);
    EXPECT_GE(coverage.arrays, 5);
    EXPECT_EQ(coverage.geometries, 0);
    EXPECT_GE(coverage.with_stale, 5);
    if (merges) {
        EXPECT_GE(coverage.after_swap, 2);
    } else {
        EXPECT_GE(coverage.fallbacks, 1);
    }
}

TEST(Differential, ThousandsOfInstancesInAnInstanceArrayMatchAFreshBuildThroughMerges) {
    run_instance_array(true);
}

TEST(Differential, ThousandsOfInstancesInAnInstanceArrayMatchAFreshBuildThroughTheFallback) {
    run_instance_array(false);
}

TEST(Differential, ThousandsOfInstancesMatchAFreshBuildThroughTheSynchronousFallback) {
    TierCoverage coverage;
    // No merges and a small dynamic tier: the fallback rebuilds the static tier now and then.
    run_many_instances(tlas_config(TlasKind::Incremental, 0.03, false), 0x7140002u, 24, coverage);
    EXPECT_GE(coverage.fallbacks, 2);
    EXPECT_GE(coverage.with_stale, 10);
    EXPECT_EQ(coverage.after_swap, 0);
}

// Groups: random trees, moves, reparenting (cycles included, which must be refused without a
// trace), hides and shows at every level, against a flat scene built from scratch with the world
// transforms and visibility the test computes itself by walking each instance's ancestors.

class RandomGroups {
public:
    explicit RandomGroups(uint64_t seed) : m_rng(seed) {}

    EditBatch initial() {
        EditBatch b;
        b.edits.emplace_back(test::mesh_edit("box", make_box(Vec3(2.0f))));
        b.edits.emplace_back(test::mesh_edit("ball", make_sphere(1.2f, 12)));
        b.edits.emplace_back(SetCamera{Vec3(0, 3, 14), Vec3(0), Vec3(0, 1, 0), 60.0f});
        for (int i = 0; i < 6; ++i) b.edits.emplace_back(add_group());
        for (int i = 0; i < 24; ++i) b.edits.emplace_back(add_instance());
        return b;
    }

    EditBatch next() {
        EditBatch b;
        const int n = integer(1, 4);
        for (int i = 0; i < n; ++i) {
            b.edits.push_back(edit());
            // The model learns what a recursive removal took only after the batch.
            if (std::holds_alternative<RemoveGroup>(b.edits.back())) break;
        }
        return b;
    }

    /// Resets the model's ids: after a refused batch, or a recursive removal.
    void reset_to(const std::vector<std::string>& groups, const std::vector<std::string>& instances) {
        m_groups = groups;
        m_instances = instances;
    }
    const std::vector<std::string>& groups() const { return m_groups; }
    const std::vector<std::string>& instances() const { return m_instances; }

private:
    Edit edit() {
        const int k = integer(0, 99);
        if (k < 20 && !m_groups.empty())
            return UpdateGroup{pick(m_groups), std::nullopt, transform(), std::nullopt};
        if (k < 35 && !m_groups.empty())
            return UpdateGroup{pick(m_groups), parent(), std::nullopt, std::nullopt};
        if (k < 50 && !m_groups.empty())
            return UpdateGroup{pick(m_groups), std::nullopt, std::nullopt, chance(0.5)};
        if (k < 60 && !m_instances.empty()) {
            UpdateInstance u;
            u.instance = pick(m_instances);
            u.parent = parent();
            return u;
        }
        if (k < 70 && !m_instances.empty()) return SetTransform{pick(m_instances), transform()};
        if (k < 76 && !m_instances.empty()) {
            UpdateInstance u;
            u.instance = pick(m_instances);
            u.visible = chance(0.7);
            return u;
        }
        if (k < 84) return add_group();
        if (k < 94) return add_instance();
        if (k < 97 && !m_instances.empty()) {
            const std::size_t i = std::size_t(integer(0, int(m_instances.size()) - 1));
            RemoveInstance r{m_instances[i]};
            m_instances.erase(m_instances.begin() + std::ptrdiff_t(i));
            return r;
        }
        if (!m_groups.empty()) {
            // Recursive removal: the model learns what went from the engine afterwards.
            return RemoveGroup{pick(m_groups), true};
        }
        return add_group();
    }

    AddGroup add_group() {
        AddGroup g;
        g.id = "g" + std::to_string(m_counter++);
        if (!m_groups.empty() && chance(0.7)) g.parent = pick(m_groups);
        g.transform = transform();
        g.visible = chance(0.9);
        m_groups.push_back(g.id);
        return g;
    }

    AddInstance add_instance() {
        AddInstance e;
        e.id = "i" + std::to_string(m_counter++);
        e.mesh = chance(0.5) ? "box" : "ball";
        e.transform = transform();
        e.visible = chance(0.9);
        if (!m_groups.empty() && chance(0.8)) e.parent = pick(m_groups);
        m_instances.push_back(e.id);
        return e;
    }

    std::optional<std::string> parent() {
        if (m_groups.empty() || chance(0.2)) return std::nullopt;
        return pick(m_groups);
    }

    Affine transform() {
        const Vec3 t(uniform(-2.5f, 2.5f), uniform(-1.5f, 1.5f), uniform(-2.5f, 2.5f));
        const Vec3 r(uniform(-30, 30), uniform(-180, 180), uniform(-30, 30));
        return Affine::trs(t, Affine::rotation_euler_deg(r), Vec3(uniform(0.7f, 1.2f)));
    }

    std::string pick(const std::vector<std::string>& v) {
        return v[std::size_t(integer(0, int(v.size()) - 1))];
    }
    float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(m_rng); }
    int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(m_rng); }
    bool chance(double p) { return std::bernoulli_distribution(p)(m_rng); }

    std::mt19937_64 m_rng;
    std::vector<std::string> m_groups;
    std::vector<std::string> m_instances;
    int m_counter = 0;
};

/// The flat scene: the meshes and camera of `s`, and each instance at the root with the world
/// transform and visibility computed here from its ancestors' local values.
EditBatch flattened_by_walking(const Scene& s, std::size_t& visible) {
    EditBatch b;
    for (Edit& e : s.to_batch().edits) {
        if (std::holds_alternative<AddMesh>(e) || std::holds_alternative<SetCamera>(e))
            b.edits.push_back(std::move(e));
    }
    visible = 0;
    s.instances().for_each([&](InstanceHandle, const InstanceRecord& i) {
        std::vector<const GroupRecord*> path;
        for (GroupHandle g = i.parent; !g.is_null(); g = s.group(g).value()->parent)
            path.push_back(s.group(g).value());
        Affine world;
        bool shown = i.visible;
        bool first = true;
        for (auto it = path.rbegin(); it != path.rend(); ++it) {
            world = first ? (*it)->transform : world * (*it)->transform;
            first = false;
            shown = shown && (*it)->visible;
        }
        world = first ? i.transform : world * i.transform;
        AddInstance e;
        e.id = i.id;
        e.mesh = s.mesh(i.mesh).value()->id;
        e.transform = world;
        e.visible = shown;
        visible += shown;
        b.edits.emplace_back(std::move(e));
    });
    return b;
}

TEST(Differential, GroupsMatchAFlatSceneBuiltFromTheWorldTransforms) {
    int launches = 0, refused = 0, hit_pixels = 0, recursive_removals = 0;
    std::size_t hidden_by_groups = 0;
    for (int seq = 0; seq < 40; ++seq) {
        RandomGroups edits(0x6A0F0000u + uint64_t(seq));
        EngineConfig config;
        config.accel.tlas = seq % 2 ? TlasKind::Embree : TlasKind::Incremental;
        auto engine = std::move(test::create_engine(config).value());
        ASSERT_TRUE(engine->apply(edits.initial()).has_value());
        for (int batch = 0; batch < 16; ++batch) {
            const auto groups_before = edits.groups();
            const auto instances_before = edits.instances();
            auto applied = engine->apply(edits.next());
            if (!applied) {
                // Only a cycle or the depth limit may refuse these batches.
                ASSERT_TRUE(applied.error().code == ErrorCode::Cycle ||
                            applied.error().code == ErrorCode::InvalidArgument)
                    << applied.error().describe();
                edits.reset_to(groups_before, instances_before);
                ++refused;
            }
            // What a recursive removal took with it.
            const auto [groups_now, instances_now] = engine->read([&](const Scene& s) {
                std::vector<std::string> g, i;
                for (const auto& id : edits.groups())
                    if (!s.find_group(id).is_null()) g.push_back(id);
                for (const auto& id : edits.instances())
                    if (!s.find_instance(id).is_null()) i.push_back(id);
                return std::pair(g, i);
            });
            recursive_removals += groups_now.size() < edits.groups().size();
            edits.reset_to(groups_now, instances_now);
            if (batch % 3 == 1) continue;  // let some batches pile up

            const HitFrame incremental = render(*engine, 0xFFFFFFFFu);
            std::size_t visible = 0;
            const EditBatch flat =
                engine->read([&](const Scene& s) { return flattened_by_walking(s, visible); });
            hidden_by_groups += engine->read([](const Scene& s) {
                std::size_t n = 0;
                s.instances().for_each([&](InstanceHandle, const InstanceRecord& i) {
                    n += i.visible && !i.world_visible;
                });
                return n;
            });
            auto scratch_engine = test::make_engine();
            ASSERT_TRUE(scratch_engine->apply(EditBatch(flat)).has_value());
            const HitFrame scratch = render(*scratch_engine, 0xFFFFFFFFu);
            const std::string diff = compare(incremental, scratch);
            ASSERT_TRUE(diff.empty()) << "sequence " << seq << " batch " << batch << " differs:\n"
                                      << diff;
            ++launches;
            for (const auto& id : incremental.instance_ids) hit_pixels += !id.empty();
        }
    }
    const double coverage = double(hit_pixels) / (double(launches) * WIDTH * HEIGHT);
    ::testing::Test::RecordProperty("launches", launches);
    ::testing::Test::RecordProperty("refused_batches", refused);
    EXPECT_GT(launches, 300);
    EXPECT_GT(refused, 5) << "cycles should be tried, and refused";
    EXPECT_GT(recursive_removals, 3);
    EXPECT_GT(hidden_by_groups, 100u) << "group hiding should be exercised";
    EXPECT_GT(coverage, 0.05) << launches << " launches";
}

}  // namespace
}  // namespace strata

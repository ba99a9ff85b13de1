// The refit policy: a small wobble keeps refitting, an explosion turns the refit into a rebuild,
// and the report says why.

#include <cmath>

#include <gtest/gtest.h>

#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using test::instance_edit;
using test::mesh_edit;

constexpr uint32_t SEGMENTS = 32;

/// Sphere vertices pushed along their normal by `amplitude * sin(frequency * angle + phase)`.
std::vector<Vec3> wobbled_sphere(float amplitude, float phase) {
    std::vector<Vec3> p = make_sphere(1.0f, SEGMENTS).positions;
    for (Vec3& v : p) v *= 1.0f + amplitude * std::sin(5.0f * std::atan2(v.z, v.x) + phase);
    return p;
}

/// Each triangle pushed out along its own centroid direction by `distance`: the shell flies apart.
ReplaceMeshTopology exploded_sphere(float distance) {
    MeshData s = make_sphere(1.0f, SEGMENTS);
    ReplaceMeshTopology out;
    out.mesh = "ball";
    out.positions.emplace();
    for (const Triangle& t : s.triangles) {
        const Vec3 c = (s.positions[t.x] + s.positions[t.y] + s.positions[t.z]) / 3.0f;
        const Vec3 push = glm::normalize(c) * distance;
        const auto base = static_cast<uint32_t>(out.positions->size());
        for (int k = 0; k < 3; ++k) out.positions->push_back(s.positions[t[k]] + push);
        out.triangles.push_back({base, base + 1, base + 2});
    }
    return out;
}

UpdateMeshPositions set_positions(std::vector<Vec3> p) {
    return UpdateMeshPositions{"ball", 0, std::move(p)};
}

class RefitPolicyTest : public ::testing::Test {
protected:
    void start(BuildOptions options, const ReplaceMeshTopology* shape = nullptr) {
        engine = test::make_engine();
        apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, SEGMENTS), options), instance_edit("b", "ball"));
        if (shape) apply_ok(*engine, *shape);
        commit_ok(*engine);
    }
    std::unique_ptr<Engine> engine;
};

TEST_F(RefitPolicyTest, SmallWobbleKeepsRefitting) {
    start({});
    for (int frame = 0; frame < 40; ++frame) {
        apply_ok(*engine, set_positions(wobbled_sphere(0.05f, 0.3f * float(frame))));
        const RebuildReport r = commit_ok(*engine);
        ASSERT_EQ(r.blas_refits, 1u) << "frame " << frame;
        ASSERT_EQ(r.blas_rebuilds, 0u) << "frame " << frame;
        EXPECT_EQ(r.refit[0].reason, BuildReason::PositionsChanged);
    }
}

TEST_F(RefitPolicyTest, ExplosionTurnsTheRefitIntoARebuild) {
    const ReplaceMeshTopology shell = exploded_sphere(0.0f);
    start({}, &shell);
    // The shell's radius grows 1.15x per frame, so its box's surface area grows 1.32x per frame:
    // one frame after a build stays under the 1.5x fast_trace limit (refit), two frames exceed
    // it (1.75x: rebuild), after which refitting resumes from the new baseline.
    std::vector<BuildReason> actions;
    for (int frame = 1; frame <= 8; ++frame) {
        const float distance = std::pow(1.15f, float(frame)) - 1.0f;
        apply_ok(*engine, set_positions(*exploded_sphere(distance).positions));
        const RebuildReport r = commit_ok(*engine);
        ASSERT_EQ(r.blas_rebuilds + r.blas_refits, 1u);
        actions.push_back(r.blas_rebuilds ? r.rebuilt[0].reason : r.refit[0].reason);
        if (r.blas_rebuilds) {
            EXPECT_NE(r.rebuilt[0].detail.find("limit"), std::string::npos) << r.rebuilt[0].detail;
        }
    }
    const BuildReason refit = BuildReason::PositionsChanged, rebuild = BuildReason::BoundsGrowth;
    const std::vector<BuildReason> expected = {refit, rebuild, refit, rebuild,
                                               refit, rebuild, refit, rebuild};
    EXPECT_EQ(actions, expected);
}

TEST_F(RefitPolicyTest, StretchingInsideTheSameBoundsIsCaughtByTriangleGrowth) {
    start({});
    // Shuffle every vertex to the antipode of a neighbour: same bounds, long thin triangles.
    std::vector<Vec3> p = make_sphere(1.0f, SEGMENTS).positions;
    std::vector<Vec3> scrambled(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) scrambled[i] = -p[(i * 7) % p.size()];
    apply_ok(*engine, set_positions(scrambled));
    const RebuildReport r = commit_ok(*engine);
    ASSERT_EQ(r.blas_rebuilds, 1u);
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::TriangleGrowth);
}

TEST_F(RefitPolicyTest, RefitLimitForcesAPeriodicRebuild) {
    start({});
    RefitPolicy policy;
    policy.fast_trace.max_refits = 3;
    engine->set_refit_policy(policy);
    std::vector<uint32_t> rebuilds;
    for (int frame = 0; frame < 8; ++frame) {
        apply_ok(*engine, set_positions(wobbled_sphere(0.01f, float(frame))));
        const RebuildReport r = commit_ok(*engine);
        rebuilds.push_back(r.blas_rebuilds);
        if (r.blas_rebuilds) {
            EXPECT_EQ(r.rebuilt[0].reason, BuildReason::RefitLimit);
        }
    }
    EXPECT_EQ(rebuilds, (std::vector<uint32_t>{0, 0, 0, 1, 0, 0, 0, 1}));
}

TEST_F(RefitPolicyTest, MeshesThatForbidRefitAlwaysRebuild) {
    start({BuildPreference::FastTrace, false});
    apply_ok(*engine, set_positions(wobbled_sphere(0.01f, 0.0f)));
    RebuildReport r = commit_ok(*engine);
    ASSERT_EQ(r.blas_rebuilds, 1u);
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::RefitNotAllowed);
    apply_ok(*engine, MarkDirty{std::string("ball"), DirtyAction::Refit});
    r = commit_ok(*engine);
    ASSERT_EQ(r.blas_rebuilds, 1u);
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::RefitNotAllowed);
}

TEST_F(RefitPolicyTest, FastBuildMeshesTolerateMoreDrift) {
    start({BuildPreference::FastBuild, true});
    // 2x surface area: over the fast_trace limit (1.5x), under the fast_build one (4x).
    std::vector<Vec3> p = make_sphere(1.0f, SEGMENTS).positions;
    for (Vec3& v : p) v *= std::sqrt(2.0f);
    apply_ok(*engine, set_positions(p));
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.blas_refits, 1u);
    EXPECT_EQ(r.blas_rebuilds, 0u);
}

TEST(RefitDecision, ExplainsEachVerdict) {
    const RefitPolicy policy;
    const BuildBaseline baseline{{10.0, 100.0}, 0};
    RefitDecision d = decide_refit(policy, {}, baseline, {11.0, 101.0}, BuildReason::PositionsChanged);
    EXPECT_FALSE(d.rebuild);
    EXPECT_EQ(d.reason, BuildReason::PositionsChanged);
    d = decide_refit(policy, {}, baseline, {16.0, 100.0}, BuildReason::RefitRequested);
    EXPECT_TRUE(d.rebuild);
    EXPECT_EQ(d.reason, BuildReason::BoundsGrowth);
    EXPECT_EQ(d.detail, "bounding-box area grew 1.60x since the last build (limit 1.50x)");
    d = decide_refit(policy, {}, baseline, {10.0, 151.0}, BuildReason::PositionsChanged);
    EXPECT_TRUE(d.rebuild);
    EXPECT_EQ(d.reason, BuildReason::TriangleGrowth);
}

}  // namespace
}  // namespace strata

// Deformation blur: a mesh's vertex keys (motion_positions) over frame time. Hits at a ray time
// must be those of a still mesh whose vertices sit where their keys say at that time; a change of
// the keys or positions rebuilds that mesh alone (Embree 3 has no refit for motion-blur BVHs),
// keys added or removed rebuild it with their own reason, and bad keys are refused.

#include <cmath>

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;

/// Vertex `p` at key `k` of `keys`: bulged, twisted and lifted more at each key (not a rigid or
/// affine motion, so no instance transform could stand in for it).
Vec3 deformed(const Vec3& p, int k, int keys) {
    const float s = float(k) / float(keys - 1);
    const float bulge = 1.0f + 0.35f * s * std::sin(3.0f * p.y + 1.0f);
    const float turn = 0.6f * s * p.y;
    return {bulge * (p.x * std::cos(turn) - p.z * std::sin(turn)), p.y + 0.4f * s * s,
            bulge * (p.x * std::sin(turn) + p.z * std::cos(turn))};
}

/// `e` with `keys` vertex keys in all (keys 1.. in motion_positions, vertex after vertex).
AddMesh with_keys(AddMesh e, int keys) {
    const std::vector<Vec3> rest = e.positions;
    e.motion_positions.clear();
    for (const Vec3& p : rest)
        for (int k = 1; k < keys; ++k) e.motion_positions.push_back(deformed(p, k, keys));
    return e;
}

/// `e`'s vertices where its keys put them at ray time `t` (evenly spaced keys, linear between).
AddMesh still_at(const AddMesh& e, float t) {
    AddMesh out = e;
    out.motion_positions.clear();
    const std::size_t n = e.positions.size();
    const std::size_t per = e.motion_positions.size() / n;
    const float x = t * float(per);
    const std::size_t k = std::min(std::size_t(x), per - 1);
    const float f = x - float(k);
    for (std::size_t v = 0; v < n; ++v) {
        const Vec3 a = k == 0 ? e.positions[v] : e.motion_positions[v * per + k - 1];
        const Vec3 b = e.motion_positions[v * per + k];
        out.positions[v] = (1.0f - f) * a + f * b;
    }
    return out;
}

SetCamera shutter_at(float time) {
    SetCamera c{Vec3(0, 1, 7), Vec3(0, 0.2f, 0), Vec3(0, 1, 0), 40.0f};
    c.shutter_open = c.shutter_close = time;
    return c;
}

AddMesh sphere_points() {
    AddMesh e;
    e.id = "dots";
    e.kind = MeshKind::Points;
    for (int i = 0; i < 40; ++i) {
        const float a = 0.5f * float(i);
        e.positions.emplace_back(1.4f * std::cos(a), -1.0f + 0.05f * float(i), 1.4f * std::sin(a));
        e.radii.push_back(0.12f + 0.004f * float(i));
    }
    return e;
}

class VertexKeys : public ::testing::TestWithParam<TlasKind> {};

TEST_P(VertexKeys, HitsAtARayTimeAreThoseOfTheVerticesInterpolatedThere) {
    for (const int keys : {2, 4}) {
        const AddMesh ball = with_keys(test::mesh_edit("ball", make_sphere(1.0f, 24)), keys);
        const AddMesh dots = with_keys(sphere_points(), keys);
        auto moving = test::make_engine(GetParam());
        ASSERT_NE(moving, nullptr);
        apply_ok(*moving, ball, dots, test::instance_edit("b", "ball", {-0.6f, 0, 0}),
                 test::instance_edit("d", "dots", {1.2f, 0, -1}));
        EXPECT_EQ(moving->read([](const Scene& s) {
            return s.meshes().at(s.find_mesh("ball")).motion_keys();
        }),
                  std::size_t(keys));
        std::vector<test::HitFrame> stills;
        for (const float t : {0.0f, 0.2f, 0.5f, 0.9f, 1.0f}) {
            SCOPED_TRACE(testing::Message() << keys << " keys at time " << t);
            apply_ok(*moving, shutter_at(t));
            auto still = test::make_engine(GetParam());
            apply_ok(*still, still_at(ball, t), still_at(dots, t),
                     test::instance_edit("b", "ball", {-0.6f, 0, 0}),
                     test::instance_edit("d", "dots", {1.2f, 0, -1}), shutter_at(t));
            stills.push_back(test::render(*still, 0xFFFFFFFFu));
            EXPECT_EQ(test::compare(test::render(*moving, 0xFFFFFFFFu), stills.back()), "");
        }
        // The keys matter: the frame at time 1 is not the rest pose's.
        EXPECT_NE(test::compare(stills.front(), stills.back()), "");
    }
}

TEST_P(VertexKeys, KeyEditsRebuildTheirMeshAlone) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    AddMesh ball = test::mesh_edit("ball", make_sphere(1.0f, 16));
    ball.build.allow_refit = true;
    const std::size_t n = ball.positions.size();
    apply_ok(*engine, with_keys(ball, 3), test::instance_edit("b", "ball"),
             test::mesh_edit("box", make_box(Vec3(1.0f))),
             test::instance_edit("x", "box", {3, 0, 0}));
    commit_ok(*engine);

    // New keys for a range of vertices, and key 0 (positions) moved: each a rebuild of that mesh
    // alone, for its positions, though it allows refits.
    UpdateMeshPositions range{"ball", 10, {}};
    range.motion_positions = std::vector<Vec3>(2 * 20, Vec3(0.1f, 0.2f, 0.3f));
    UpdateMeshPositions first{"ball", 0, std::vector<Vec3>(5, Vec3(0.0f, 1.0f, 0.0f))};
    for (const Edit& edit : {Edit(range), Edit(first)}) {
        apply_ok(*engine, edit);
        RebuildReport r = commit_ok(*engine);
        ASSERT_EQ(test::ids(r.rebuilt), std::vector<std::string>{"ball"});
        EXPECT_EQ(r.rebuilt[0].reason, BuildReason::PositionsChanged);
        EXPECT_NE(r.rebuilt[0].detail.find("no refit"), std::string::npos);
        EXPECT_EQ(r.blas_refits, 0u);
        EXPECT_EQ(r.tlas_action, TlasAction::Update);  // its one instance: the README's rows
    }

    // Keys removed, then added back with another count: each a rebuild of that mesh alone; still
    // in between, its moved positions refit.
    UpdateMeshPositions removed{"ball", 0, {}};
    removed.motion_positions = std::vector<Vec3>{};
    apply_ok(*engine, removed);
    RebuildReport r = commit_ok(*engine);
    ASSERT_EQ(test::ids(r.rebuilt), std::vector<std::string>{"ball"});
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::KeysChanged);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(engine->read([](const Scene& s) {
        return s.meshes().at(s.find_mesh("ball")).motion_keys();
    }),
              1u);
    apply_ok(*engine, first);
    r = commit_ok(*engine);
    EXPECT_EQ(test::ids(r.refit), std::vector<std::string>{"ball"});
    EXPECT_EQ(r.blas_rebuilds, 0u);
    UpdateMeshPositions added{"ball", 0, {}};
    added.motion_positions = std::vector<Vec3>(n, Vec3(0.0f, 0.5f, 0.0f));
    apply_ok(*engine, added);
    r = commit_ok(*engine);
    ASSERT_EQ(test::ids(r.rebuilt), std::vector<std::string>{"ball"});
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::KeysChanged);

    // After all of it, hits at several times are those of a fresh build of the same scene.
    for (const float t : {0.0f, 0.4f, 1.0f}) {
        SCOPED_TRACE(t);
        apply_ok(*engine, shutter_at(t));
        auto fresh = test::make_engine(GetParam());
        auto rebuilt =
            fresh->apply(engine->read([](const Scene& s) { return s.image().to_batch(); }));
        ASSERT_TRUE(rebuilt.has_value()) << rebuilt.error().describe();
        EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                test::render(*fresh, 0xFFFFFFFFu)),
                  "");
    }
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, VertexKeys,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

TEST(VertexKeys, BadKeysAreRefusedAndChangeNothing) {
    auto engine = test::make_engine();
    const AddMesh box = test::mesh_edit("box", make_box(Vec3(1.0f)));  // 8 vertices
    apply_ok(*engine, box, test::instance_edit("a", "box"));
    const uint64_t version = engine->read([](const Scene& s) { return s.version(); });
    auto refused = [&](Edit edit, const std::string& field) {
        test::expect_refused(*engine, std::move(edit), field);
    };
    AddMesh uneven = box;
    uneven.id = "uneven";
    uneven.motion_positions = std::vector<Vec3>(12, Vec3(0.0f));  // 1.5 per vertex
    refused(uneven, "motion_positions");
    AddMesh too_many = box;
    too_many.id = "too_many";
    too_many.motion_positions = std::vector<Vec3>(8 * MAX_MOTION_KEYS, Vec3(0.0f));
    refused(too_many, "motion_positions");
    AddMesh nan = with_keys(box, 3);
    nan.id = "nan";
    nan.motion_positions[5].y = std::nanf("");  // vertex 2 at key 2
    refused(nan, "motion_positions/16");
    // A mesh without keys takes them only whole; one with keys keeps its count per vertex.
    UpdateMeshPositions part{"box", 2, {}};
    part.motion_positions = std::vector<Vec3>(2, Vec3(0.0f));
    refused(part, "motion_positions");
    apply_ok(*engine, with_keys([&] {
                 AddMesh e = box;
                 e.id = "keyed";
                 return e;
             }(), 3));
    const uint64_t keyed_version = engine->read([](const Scene& s) { return s.version(); });
    UpdateMeshPositions odd{"keyed", 0, {}};
    odd.motion_positions = std::vector<Vec3>(3, Vec3(0.0f));  // keyed has 2 per vertex
    refused(odd, "motion_positions");
    UpdateMeshPositions outside{"keyed", 6, {}};
    outside.motion_positions = std::vector<Vec3>(6, Vec3(0.0f));  // vertices 6..8
    refused(outside, "motion_positions");
    ReplaceMeshTopology fewer{"keyed", std::vector<Vec3>(4, Vec3(0.0f)), {{0, 1, 2}, {0, 2, 3}}};
    refused(fewer, "motion_positions");  // 4 vertices: the 8 vertices' keys no longer fit
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), keyed_version);
    EXPECT_GT(keyed_version, version);
}

TEST(VertexKeys, TheVertexBudgetCountsEveryKey) {
    // 100 positions: a box's 8 vertices with 3 keys each (8 + 16) fit, 12 keys each (8 + 88) too,
    // 13 (8 + 96) do not; removal, topology changes, a refused batch and clear keep the count.
    EngineConfig config;
    config.budget = {1u << 20, 100};
    auto created = test::create_engine(config);
    ASSERT_TRUE(created.has_value());
    Engine& engine = *created.value();
    const AddMesh box = test::mesh_edit("box", make_box(Vec3(1.0f)));
    auto key_positions = [&] {
        return engine.read([](const Scene& s) { return s.mesh_totals().key_positions; });
    };
    apply_ok(engine, with_keys(box, 3));
    EXPECT_EQ(key_positions(), 16u);
    UpdateMeshPositions removed{"box", 0, {}};
    removed.motion_positions = std::vector<Vec3>{};
    UpdateMeshPositions twelve{"box", 0, {}};
    twelve.motion_positions = std::vector<Vec3>(8 * 11, Vec3(0.5f));
    apply_ok(engine, removed, twelve);
    EXPECT_EQ(key_positions(), 88u);
    UpdateMeshPositions thirteen = twelve;
    thirteen.motion_positions = std::vector<Vec3>(8 * 12, Vec3(0.5f));
    EditBatch over;
    over.edits.emplace_back(removed);
    over.edits.emplace_back(thirteen);
    auto r = engine.apply(std::move(over));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_NE(r.error().message.find("96 vertex keys"), std::string::npos) << r.error().message;
    EXPECT_EQ(key_positions(), 88u);  // the refused batch changed nothing
    // A topology change to 4 vertices with 2 keys each, then the mesh removed by a clear.
    ReplaceMeshTopology fewer{"box", std::vector<Vec3>(4, Vec3(0.0f)), {{0, 1, 2}, {0, 2, 3}}};
    fewer.motion_positions = std::vector<Vec3>(4 * 2, Vec3(1.0f));
    apply_ok(engine, fewer);
    EXPECT_EQ(key_positions(), 8u);
    apply_ok(engine, Clear{});
    EXPECT_EQ(key_positions(), 0u);
}

}  // namespace
}  // namespace strata

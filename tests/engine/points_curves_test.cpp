// Points and curves (mesh_kind.h): hits against analytic answers, the rules of their edits, what
// a commit does with them, and incremental commits against a fresh build of the same scene.

#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;

AddMesh points(const std::string& id, std::vector<Vec3> at, std::vector<float> radii) {
    AddMesh e;
    e.id = id;
    e.kind = MeshKind::Points;
    e.positions = std::move(at);
    e.radii = std::move(radii);
    return e;
}

/// Straight strands along x at heights `ys`, each of `per_strand` control vertices from x = -2
/// to x = 2, radius `radius`.
AddMesh curves(const std::string& id, CurveBasis basis, CurveStyle style,
               const std::vector<float>& ys, uint32_t per_strand, float radius) {
    AddMesh e;
    e.id = id;
    e.kind = MeshKind::Curves;
    e.basis = basis;
    e.style = style;
    for (float y : ys) {
        e.strands.push_back(per_strand);
        for (uint32_t k = 0; k < per_strand; ++k) {
            e.positions.emplace_back(-2.0f + 4.0f * float(k) / float(per_strand - 1), y, 0.0f);
            e.radii.push_back(radius);
        }
    }
    return e;
}

/// The first hit through the centre of a 101x101 image, looking down -z from (x, y, 10).
std::optional<PickHit> pick_from(Engine& engine, float x, float y) {
    PickRequest request;
    request.width = request.height = 101;
    request.pixels = {{50, 50}};
    request.camera = SetCamera{Vec3(x, y, 10.0f), Vec3(x, y, 0.0f), Vec3(0, 1, 0), 20.0f};
    auto result = engine.pick(request);
    EXPECT_TRUE(result.has_value()) << (result ? "" : result.error().describe());
    return result ? result.value().hits.at(0) : std::nullopt;
}

TEST(PointsAndCurves, SpheresAreHitWhereTheirCentresAndRadiiSay) {
    auto engine = test::make_engine();
    apply_ok(*engine, points("p", {{0, 0, 0}, {3, 0, 0}}, {1.0f, 0.5f}),
             test::instance_edit("i", "p"));
    auto hit = pick_from(*engine, 0.0f, 0.0f);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->mesh, "p");
    EXPECT_EQ(hit->primitive, 0u);
    EXPECT_NEAR(hit->distance, 9.0f, 1e-4f);
    EXPECT_NEAR(hit->normal.z, 1.0f, 1e-4f);
    hit = pick_from(*engine, 3.0f, 0.0f);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->primitive, 1u);
    EXPECT_NEAR(hit->distance, 9.5f, 1e-4f);
    EXPECT_FALSE(pick_from(*engine, 1.6f, 0.0f));

    // A radius update moves the surface; a new point count is a new set of points.
    UpdateMeshPositions grow;
    grow.mesh = "p";
    grow.offset = 1;
    grow.radii = std::vector<float>{0.75f};
    apply_ok(*engine, grow);
    hit = pick_from(*engine, 3.0f, 0.0f);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance, 9.25f, 1e-4f);
    ReplaceMeshTopology three;
    three.mesh = "p";
    three.positions = {{0, 0, 0}, {3, 0, 0}, {-3, 0, 2}};
    three.radii = std::vector<float>{1.0f, 0.5f, 0.25f};
    apply_ok(*engine, three);
    hit = pick_from(*engine, -3.0f, 0.0f);
    ASSERT_TRUE(hit);
    EXPECT_EQ(hit->primitive, 2u);
    EXPECT_NEAR(hit->distance, 7.75f, 1e-4f);
}

TEST(PointsAndCurves, CurvesInEveryBasisAreHitAtTheirRadiusAndReportTheirSegment) {
    struct Case {
        CurveBasis basis;
        uint32_t per_strand;
        uint32_t segments;  ///< per strand
    };
    for (const Case c : {Case{CurveBasis::Linear, 5, 4}, Case{CurveBasis::Bezier, 7, 2},
                         Case{CurveBasis::BSpline, 6, 3}, Case{CurveBasis::CatmullRom, 6, 3}}) {
        for (const CurveStyle style : {CurveStyle::Round, CurveStyle::Flat}) {
            SCOPED_TRACE(int(c.basis) * 2 + int(style));
            auto engine = test::make_engine();
            apply_ok(*engine, curves("c", c.basis, style, {0.0f, 1.0f}, c.per_strand, 0.25f),
                     test::instance_edit("i", "c"));
            // The second strand at its middle: past the first strand's segments. A B-spline's
            // straight control polygon makes a straight curve too (it lies inside the hull).
            const auto hit = pick_from(*engine, 0.05f, 1.0f);
            ASSERT_TRUE(hit);
            EXPECT_EQ(hit->mesh, "c");
            EXPECT_GE(hit->primitive, c.segments);
            EXPECT_LT(hit->primitive, 2 * c.segments);
            // A round tube's front is a radius nearer than its axis; a flat ribbon faces the ray.
            const float expected = style == CurveStyle::Round ? 9.75f : 10.0f;
            EXPECT_NEAR(hit->distance, expected, 2e-3f);
            EXPECT_FALSE(pick_from(*engine, 0.0f, 0.5f)) << "between the strands";
            const RebuildReport report = commit_ok(*engine);
            EXPECT_TRUE(report.rebuilt.empty() && report.refit.empty());
        }
    }
}

// Embree 3 has no refit for spheres and curves: every geometry edit rebuilds that mesh alone, with
// the reason saying what changed.
TEST(PointsAndCurves, EachEditRebuildsOnlyTheMeshItChangedWithItsReason) {
    auto engine = test::make_engine();
    apply_ok(*engine, points("p", {{0, 0, 0}, {3, 0, 0}}, {1.0f, 0.5f}),
             curves("c", CurveBasis::Bezier, CurveStyle::Round, {0.0f, 1.0f}, 4, 0.1f),
             test::instance_edit("ip", "p"), test::instance_edit("ic", "c", {0, 3, 0}));
    RebuildReport r = commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 2u);
    EXPECT_EQ(r.primitives_built, 2u + 2u);  // two points, two one-segment strands

    UpdateMeshPositions moved;
    moved.mesh = "p";
    moved.positions = {{0, 0.5f, 0}};
    UpdateMeshPositions thicker;
    thicker.mesh = "c";
    thicker.offset = 4;
    thicker.radii = std::vector<float>{0.2f, 0.2f, 0.2f, 0.2f};
    apply_ok(*engine, moved, thicker);
    r = commit_ok(*engine);
    EXPECT_TRUE(r.refit.empty());
    ASSERT_EQ(r.rebuilt.size(), 2u);
    for (const MeshBuildEntry& e : r.rebuilt) {
        EXPECT_EQ(e.reason, BuildReason::PositionsChanged);
        EXPECT_NE(e.detail.find("no refit"), std::string::npos) << e.detail;
    }
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    apply_ok(*engine, thicker);  // radii alone
    r = commit_ok(*engine);
    ASSERT_EQ(test::ids(r.rebuilt), std::vector<std::string>{"c"});
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::PositionsChanged);

    ReplaceMeshTopology strand;
    strand.mesh = "c";
    strand.positions = std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 1, 0},
                                         {5, 1, 0}, {6, 1, 0}};
    strand.radii = std::vector<float>(7, 0.1f);
    strand.strands = std::vector<uint32_t>{7};
    apply_ok(*engine, strand);
    r = commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u);
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::TopologyChanged);
    EXPECT_EQ(r.rebuilt[0].primitives, 2u);
}

/// Applies `edit` alone, which must be refused with `code` at `field`, leaving the scene as it
/// was.
void expect_refused(Engine& engine, Edit edit, ErrorCode code, const std::string& field) {
    const uint64_t before = engine.read([](const Scene& s) { return s.version(); });
    EditBatch batch;
    batch.edits.push_back(std::move(edit));
    auto r = engine.apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, code) << r.error().describe();
    EXPECT_EQ(r.error().field, field) << r.error().describe();
    EXPECT_EQ(engine.read([](const Scene& s) { return s.version(); }), before);
}

/// An engine holding points "p" (2), a linear curve "c" (one strand of 3) and a box "t".
std::unique_ptr<Engine> three_kinds() {
    auto engine = test::make_engine();
    apply_ok(*engine, points("p", {{0, 0, 0}, {1, 0, 0}}, {0.5f, 0.5f}),
             curves("c", CurveBasis::Linear, CurveStyle::Round, {0.0f}, 3, 0.1f),
             test::mesh_edit("t", make_box(Vec3(1.0f))));
    return engine;
}

TEST(PointsAndCurves, BadNewPointsAndCurvesAreRefusedAndChangeNothing) {
    auto engine = three_kinds();
    using E = ErrorCode;

    AddMesh no_radii = points("q", {{0, 0, 0}}, {});
    expect_refused(*engine, no_radii, E::InvalidArgument, "radii");
    AddMesh negative = points("q", {{0, 0, 0}}, {-1.0f});
    expect_refused(*engine, negative, E::InvalidArgument, "radii/0");
    AddMesh nan = points("q", {{0, 0, 0}, {1, 1, 1}}, {1.0f, std::nanf("")});
    expect_refused(*engine, nan, E::NotFinite, "radii/1");
    AddMesh short_radii = points("q", {{0, 0, 0}, {1, 1, 1}}, {1.0f});
    expect_refused(*engine, short_radii, E::InvalidArgument, "radii");
    AddMesh indexed = points("q", {{0, 0, 0}}, {1.0f});
    indexed.triangles = {{0, 0, 0}};
    expect_refused(*engine, indexed, E::InvalidArgument, "indices");
    AddMesh shaded = points("q", {{0, 0, 0}}, {1.0f});
    shaded.normals = {{0, 1, 0}};
    expect_refused(*engine, shaded, E::InvalidArgument, "normals");
    AddMesh bezier = curves("q", CurveBasis::Bezier, CurveStyle::Round, {0.0f}, 5, 0.1f);
    expect_refused(*engine, bezier, E::InvalidArgument, "strands/0");
    AddMesh sum = curves("q", CurveBasis::Linear, CurveStyle::Round, {0.0f}, 4, 0.1f);
    sum.strands = {2, 1, 1};
    expect_refused(*engine, sum, E::InvalidArgument, "strands/1");
    sum.strands = {2};
    expect_refused(*engine, sum, E::InvalidArgument, "strands");
    AddMesh strandless = curves("q", CurveBasis::Linear, CurveStyle::Round, {0.0f}, 4, 0.1f);
    strandless.strands.clear();
    expect_refused(*engine, strandless, E::InvalidArgument, "strands");
    AddMesh tube = test::mesh_edit("q", make_box(Vec3(1.0f)));
    tube.radii.assign(tube.positions.size(), 1.0f);
    expect_refused(*engine, tube, E::InvalidArgument, "radii");
    tube.radii.clear();
    tube.basis = CurveBasis::Bezier;
    expect_refused(*engine, tube, E::InvalidArgument, "basis");
}

TEST(PointsAndCurves, BadEditsOfPointsAndCurvesAreRefusedAndChangeNothing) {
    auto engine = three_kinds();
    using E = ErrorCode;
    UpdateMeshPositions drop;
    drop.mesh = "p";
    drop.radii = std::vector<float>{};
    expect_refused(*engine, drop, E::InvalidArgument, "radii");
    UpdateMeshPositions past;
    past.mesh = "c";
    past.offset = 2;
    past.radii = std::vector<float>{0.1f, 0.1f};
    expect_refused(*engine, past, E::OutOfRange, "radii");
    UpdateMeshPositions regrow;
    regrow.mesh = "c";
    regrow.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    expect_refused(*engine, regrow, E::OutOfRange, "positions");
    UpdateMeshPositions more_points;  // a new count is a topology change (resize on the wire)
    more_points.mesh = "p";
    more_points.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    expect_refused(*engine, more_points, E::OutOfRange, "positions");
    ReplaceMeshTopology radii_kept{"p", more_points.positions, {}};
    expect_refused(*engine, radii_kept, E::InvalidArgument, "radii");
    ReplaceMeshTopology strands_of_points;
    strands_of_points.mesh = "p";
    strands_of_points.strands = std::vector<uint32_t>{2};
    expect_refused(*engine, strands_of_points, E::InvalidArgument, "strands");
    ReplaceMeshTopology bad_strands;
    bad_strands.mesh = "c";
    bad_strands.strands = std::vector<uint32_t>{1, 2};
    expect_refused(*engine, bad_strands, E::InvalidArgument, "strands/0");
    expect_refused(*engine, ReplaceMeshTriangles{"c", 0, 1, {}}, E::InvalidArgument, "mesh");
}

/// A random points or curve edit that keeps the scene valid, given each mesh's kind and counts.
struct Mutator {
    std::mt19937 rng{7};
    float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }

    Edit next(const Scene& scene) {
        const bool on_points = rng() % 2 == 0;
        const MeshRecord& m = *scene.mesh(scene.find_mesh(on_points ? "p" : "c")).value();
        const auto n = uint32_t(m.positions.size());
        switch (rng() % 4) {
            case 0: {  // a range of positions and maybe radii
                UpdateMeshPositions u;
                u.mesh = m.id;
                u.offset = uint32_t(rng() % n);
                const uint32_t count = 1 + uint32_t(rng() % (n - u.offset));
                for (uint32_t i = 0; i < count; ++i)
                    u.positions.push_back(m.positions[u.offset + i] +
                                          Vec3(uniform(-0.3f, 0.3f), uniform(-0.3f, 0.3f), 0));
                if (rng() % 2) u.radii = std::vector<float>(count, uniform(0.05f, 0.4f));
                return u;
            }
            case 1: {  // scattered vertices
                UpdateMeshVertices u;
                u.mesh = m.id;
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = uint32_t(rng() % n);
                    u.vertices.push_back(v);
                    u.positions.push_back(m.positions[v] + Vec3(0, uniform(-0.5f, 0.5f), 0));
                }
                return u;
            }
            default: {  // a new count
                const uint32_t count = 4 + uint32_t(rng() % 40);
                ReplaceMeshTopology t;
                t.mesh = m.id;
                t.positions.emplace();
                for (uint32_t i = 0; i < count; ++i)
                    t.positions->emplace_back(uniform(-3, 3), uniform(-2, 2), uniform(-1, 1));
                t.radii = std::vector<float>(count, uniform(0.05f, 0.3f));
                if (!on_points) t.strands = std::vector<uint32_t>{count / 2, count - count / 2};
                return t;
            }
        }
    }
};

TEST(PointsAndCurves, IncrementalCommitsMatchAFreshBuildOfTheSameScene) {
    auto engine = test::make_engine();
    std::vector<float> ys;
    for (int k = 0; k < 6; ++k) ys.push_back(-1.5f + 0.6f * float(k));
    apply_ok(*engine,
             points("p", {{-1, 0, 0.5f}, {1, 0.5f, 0}, {0, -1, -0.5f}, {2, 1, 0}},
                    {0.4f, 0.3f, 0.5f, 0.2f}),
             curves("c", CurveBasis::CatmullRom, CurveStyle::Round, ys, 6, 0.08f),
             test::instance_edit("ip", "p"), test::instance_edit("ic", "c", {0, 0, 0.3f}),
             SetCamera{Vec3(0, 0, 8), Vec3(0, 0, 0), Vec3(0, 1, 0), 45.0f});
    Mutator mutate;
    int applied = 0;
    for (int round = 0; round < 40; ++round) {
        SCOPED_TRACE(round);
        EditBatch batch;
        for (int k = 0; k < 3; ++k)
            batch.edits.push_back(engine->read([&](const Scene& s) { return mutate.next(s); }));
        // Edits chosen from the scene before the batch may clash within it (a range on a mesh an
        // earlier edit resized): such a batch is refused whole, which is part of the test.
        if (!engine->apply(std::move(batch)).has_value()) continue;
        ++applied;
        const test::HitFrame incremental = test::render(*engine, 0xFFFFFFFFu);
        auto fresh = test::make_engine();
        auto rebuilt =
            fresh->apply(engine->read([](const Scene& s) { return s.image().to_batch(); }));
        ASSERT_TRUE(rebuilt.has_value()) << rebuilt.error().describe();
        const test::HitFrame scratch = test::render(*fresh, 0xFFFFFFFFu);
        EXPECT_EQ(test::compare(incremental, scratch), "");
    }
    EXPECT_GE(applied, 20) << "most batches must apply for the comparison to mean something";
}

/// Renders race a stream of point and curve edits (each a rebuild): every frame shows exactly one
/// committed version, the one a fresh build of the same edits shows (run under TSan too).
TEST(PointsAndCurves, RendersDuringEditsTraceExactlyOneVersion) {
    constexpr int BATCHES = 60;
    std::vector<float> ys;
    for (int k = 0; k < 5; ++k) ys.push_back(-1.0f + 0.5f * float(k));
    EditBatch initial;
    initial.edits.emplace_back(points("p", {{-1, 0, 0.5f}, {1, 0.5f, 0}, {0, -1, -0.5f}},
                                      {0.4f, 0.3f, 0.5f}));
    initial.edits.emplace_back(curves("c", CurveBasis::Bezier, CurveStyle::Round, ys, 4, 0.1f));
    initial.edits.emplace_back(test::instance_edit("ip", "p"));
    initial.edits.emplace_back(test::instance_edit("ic", "c", {0, 0, 0.3f}));
    initial.edits.emplace_back(SetCamera{Vec3(0, 0, 8), Vec3(0), Vec3(0, 1, 0), 45.0f});
    std::vector<EditBatch> batches;
    std::mt19937 rng(9);
    for (int i = 0; i < BATCHES; ++i) {
        EditBatch b;
        const float dy = std::uniform_real_distribution<float>(-0.5f, 0.5f)(rng);
        UpdateMeshPositions moved{"p", uint32_t(rng() % 3), {Vec3(0.5f, dy, 0.0f)}};
        UpdateMeshPositions thicker{"c", 4 * uint32_t(rng() % 5), {}};
        thicker.radii = std::vector<float>(4, 0.05f + 0.2f * std::abs(dy));
        b.edits.emplace_back(std::move(moved));
        b.edits.emplace_back(std::move(thicker));
        batches.push_back(std::move(b));
    }
    auto engine = test::make_engine();
    ASSERT_TRUE(engine->apply(EditBatch(initial)).has_value());
    test::commit_ok(*engine);
    const uint64_t base = engine->read([](const Scene& s) { return s.version(); });

    std::atomic<int> next{0};
    std::thread editor([&] {
        for (; next.load() < BATCHES; next.fetch_add(1)) {
            if (!engine->apply(EditBatch(batches[std::size_t(next.load())])).has_value()) break;
            std::this_thread::sleep_for(std::chrono::microseconds(300));
        }
    });
    std::vector<std::pair<uint64_t, test::HitFrame>> shown;
    while (shown.size() < 5 || (shown.size() < 30 && next.load() < BATCHES)) {
        RebuildReport report;
        test::HitFrame frame = test::render(*engine, 0xFFFFFFFFu, &report, 64, 48);
        shown.emplace_back(report.version, std::move(frame));
    }
    editor.join();
    ASSERT_EQ(next.load(), BATCHES) << "every batch applies";
    for (const auto& [version, frame] : shown) {
        ASSERT_GE(version, base);
        const uint64_t applied = version - base;
        ASSERT_LE(applied, uint64_t(BATCHES));
        auto fresh = test::make_engine();
        ASSERT_TRUE(fresh->apply(EditBatch(initial)).has_value());
        for (uint64_t i = 0; i < applied; ++i)
            ASSERT_TRUE(fresh->apply(EditBatch(batches[i])).has_value());
        EXPECT_EQ(test::compare(frame, test::render(*fresh, 0xFFFFFFFFu, nullptr, 64, 48)), "")
            << "frame of version " << version;
    }
}

}  // namespace
}  // namespace strata

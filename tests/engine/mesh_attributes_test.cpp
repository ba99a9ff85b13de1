// Per-vertex normals, uvs and tangents: the scene's rules for them (counts, values, partial
// updates, topology changes), rollback of refused batches, undo, and their journal encoding.

#include <string>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;

/// A quad of 4 vertices facing +z.
AddMesh quad(const std::string& id) {
    AddMesh m;
    m.id = id;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    m.triangles = {{0, 1, 2}, {1, 3, 2}};
    return m;
}

Error refused(Engine& engine, Edit edit) {
    EditBatch b;
    b.edits.push_back(std::move(edit));
    auto r = engine.apply(std::move(b));
    EXPECT_FALSE(r.has_value());
    return r.has_value() ? Error{} : r.error();
}

/// The mesh's normals and uvs as the scene holds them.
std::pair<std::vector<Vec3>, std::vector<Vec2>> attributes(const Engine& engine,
                                                           const std::string& id) {
    return engine.read([&](const Scene& s) {
        const MeshRecord* m = s.mesh(s.find_mesh(id)).value();
        return std::make_pair(m->normals, m->uvs);
    });
}

TEST(MeshAttributes, AMeshKeepsTheNormalsAndUvsItWasAddedWith) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.normals = {{0, 0, 1}, {0, 0, 2}, {0, 0.5f, 1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    apply_ok(*engine, m);
    const auto [normals, uvs] = attributes(*engine, "q");
    EXPECT_EQ(normals, m.normals);
    EXPECT_EQ(uvs, m.uvs);
}

TEST(MeshAttributes, CountsOtherThanTheVertexCountAreRefusedNamingTheMember) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    Error e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field, "normals");
    EXPECT_NE(e.message.find("3 entries"), std::string::npos) << e.message;

    m = quad("q");
    m.uvs = {{0, 0}};
    e = refused(*engine, m);
    EXPECT_EQ(e.field, "uvs");
}

TEST(MeshAttributes, ZeroOrNonFiniteNormalsAndNonFiniteUvsAreRefused) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 0}, {0, 0, 1}};
    Error e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field, "normals/6");
    EXPECT_NE(e.message.find("vertex 2 is zero"), std::string::npos) << e.message;

    m.normals[2] = Vec3(0, std::nanf(""), 1);
    e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::NotFinite);

    m = quad("q");
    m.uvs = {{0, 0}, {1, 0}, {0, INFINITY}, {1, 1}};
    e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::NotFinite);
    EXPECT_EQ(e.field, "uvs/5");
}

TEST(MeshAttributes, PartialUpdatesNeedNormalsToExistAndStayInsideTheMesh) {
    auto engine = test::make_engine();
    apply_ok(*engine, quad("q"));
    UpdateMeshPositions part;
    part.mesh = "q";
    part.offset = 1;
    part.normals = std::vector<Vec3>{{0, 0, 1}};
    Error e = refused(*engine, part);
    EXPECT_EQ(e.field, "normals");
    EXPECT_NE(e.message.find("has no normals yet"), std::string::npos) << e.message;

    UpdateMeshPositions whole;
    whole.mesh = "q";
    whole.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    apply_ok(*engine, whole);
    apply_ok(*engine, part);
    EXPECT_EQ(attributes(*engine, "q").first[1], Vec3(0, 0, 1));

    part.offset = 3;
    part.normals = std::vector<Vec3>{{0, 1, 1}, {0, 1, 1}};
    e = refused(*engine, part);
    EXPECT_EQ(e.code, ErrorCode::OutOfRange);

    part.offset = 2;
    apply_ok(*engine, part);
    const auto normals = attributes(*engine, "q").first;
    EXPECT_EQ(normals[1], Vec3(0, 0, 1));
    EXPECT_EQ(normals[2], Vec3(0, 1, 1));
    EXPECT_EQ(normals[3], Vec3(0, 1, 1));

    UpdateMeshPositions remove;
    remove.mesh = "q";
    remove.normals = std::vector<Vec3>{};
    apply_ok(*engine, remove);
    EXPECT_TRUE(attributes(*engine, "q").first.empty());

    UpdateMeshPositions nothing;
    nothing.mesh = "q";
    e = refused(*engine, nothing);
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
}

TEST(MeshAttributes, ATopologyChangeOfTheVertexCountMustBringNewNormals) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    apply_ok(*engine, m);

    ReplaceMeshTopology smaller;
    smaller.mesh = "q";
    smaller.positions = std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    smaller.triangles = {{0, 1, 2}};
    Error e = refused(*engine, smaller);
    EXPECT_EQ(e.field, "normals");
    EXPECT_NE(e.message.find("needs new normals"), std::string::npos) << e.message;

    // Same vertex count: the normals stay.
    ReplaceMeshTopology flipped;
    flipped.mesh = "q";
    flipped.triangles = {{0, 2, 1}, {1, 2, 3}};
    apply_ok(*engine, flipped);
    EXPECT_EQ(attributes(*engine, "q").first.size(), 4u);

    smaller.normals = std::vector<Vec3>(3, Vec3(0, 0, 1));
    smaller.uvs = std::vector<Vec2>(3, Vec2(0.5f));
    apply_ok(*engine, smaller);
    EXPECT_EQ(attributes(*engine, "q").first.size(), 3u);
    EXPECT_EQ(attributes(*engine, "q").second.size(), 3u);

    smaller.normals = std::vector<Vec3>{};
    smaller.uvs = std::vector<Vec2>(2, Vec2(0.5f));
    e = refused(*engine, smaller);
    EXPECT_EQ(e.field, "uvs");
}

TEST(MeshAttributes, ARefusedBatchPutsTheOldNormalsAndUvsBack) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    apply_ok(*engine, m);
    const auto before = attributes(*engine, "q");

    UpdateMeshPositions part;
    part.mesh = "q";
    part.offset = 1;
    part.normals = std::vector<Vec3>{{1, 0, 0}, {1, 0, 0}};
    part.uvs = std::vector<Vec2>{};
    ReplaceMeshTopology topo;
    topo.mesh = "q";
    topo.triangles = {{0, 2, 1}};
    topo.normals = std::vector<Vec3>(4, Vec3(0, 1, 0));
    EditBatch b;
    b.edits.emplace_back(part);
    b.edits.emplace_back(topo);
    b.edits.emplace_back(RemoveMesh{"no-such-mesh"});
    ASSERT_FALSE(engine->apply(std::move(b)).has_value());
    EXPECT_EQ(attributes(*engine, "q"), before);
}

TEST(MeshAttributes, JournalCodecCarriesThemAndLeavesOtherEditsAsBefore) {
    EditBatch plain;
    plain.edits.emplace_back(quad("q"));
    std::string plain_bytes;
    durable::encode_batch(plain, plain_bytes);
    EXPECT_EQ(uint8_t(plain_bytes[4]), 0u) << "an add_mesh without attributes keeps kind tag 0";

    EditBatch b;
    AddMesh m = quad("q");
    m.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    b.edits.emplace_back(m);
    UpdateMeshPositions u;
    u.mesh = "q";
    u.offset = 2;
    u.normals = std::vector<Vec3>{{0, 1, 0}};
    b.edits.emplace_back(u);
    ReplaceMeshTopology t;
    t.mesh = "q";
    t.triangles = {{0, 1, 2}};
    t.uvs = std::vector<Vec2>{};
    b.edits.emplace_back(t);
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    const auto& m2 = std::get<AddMesh>(back->edits[0]);
    EXPECT_EQ(m2.normals, m.normals);
    EXPECT_EQ(m2.uvs, m.uvs);
    const auto& u2 = std::get<UpdateMeshPositions>(back->edits[1]);
    EXPECT_EQ(u2.offset, 2u);
    EXPECT_EQ(u2.normals, u.normals);
    EXPECT_FALSE(u2.uvs.has_value());
    const auto& t2 = std::get<ReplaceMeshTopology>(back->edits[2]);
    EXPECT_FALSE(t2.normals.has_value());
    ASSERT_TRUE(t2.uvs.has_value());
    EXPECT_TRUE(t2.uvs->empty());
    std::string again;
    durable::encode_batch(back.value(), again);
    EXPECT_EQ(again, bytes);
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(durable::decode_batch(std::string_view(bytes).substr(0, n)).has_value()) << n;
}

// Step: tangents ---------------------------------------------------------------------------------

std::vector<Vec4> tangents_of(const Engine& engine, const std::string& id) {
    return engine.read([&](const Scene& s) { return s.mesh(s.find_mesh(id)).value()->tangents; });
}

/// Applies the inverse of the newest batch.
void undo_last(Engine& engine) {
    auto inverse = engine.undo_batch(engine.version());
    ASSERT_TRUE(inverse.has_value()) << inverse.error().describe();
    ASSERT_TRUE(engine.apply(std::move(inverse.value()), engine.version()).has_value());
}

AddMesh quad_with_tangents(const std::string& id) {
    AddMesh m = quad(id);
    m.normals = std::vector<Vec3>(4, Vec3(0, 0, 1));
    m.uvs = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
    m.tangents = std::vector<Vec4>(4, Vec4(1, 0, 0, 1));
    return m;
}

TEST(MeshTangents, EachIsADirectionWithWPlusOrMinusOneOnePerVertex) {
    auto engine = test::make_engine();
    AddMesh m = quad_with_tangents("q");
    m.tangents.pop_back();
    Error e = refused(*engine, m);
    EXPECT_EQ(e.field, "tangents");
    EXPECT_NE(e.message.find("3 entries"), std::string::npos) << e.message;

    m = quad_with_tangents("q");
    m.tangents[1].w = 0.5f;
    e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field, "tangents/7");
    EXPECT_NE(e.message.find("+1 or -1"), std::string::npos) << e.message;

    m.tangents[1] = Vec4(0, 0, 0, 1);
    e = refused(*engine, m);
    EXPECT_EQ(e.field, "tangents/4");
    EXPECT_NE(e.message.find("vertex 1 is zero"), std::string::npos) << e.message;

    m.tangents[1] = Vec4(1, std::nanf(""), 0, 1);
    e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::NotFinite);

    m.tangents[1] = Vec4(0, 1, 0, -1);
    apply_ok(*engine, m);
    EXPECT_EQ(tangents_of(*engine, "q"), m.tangents);
}

TEST(MeshTangents, UpdatesPatchRangesTouchNoBvhAndUndoPutsThemBack) {
    auto engine = test::make_engine();
    AddMesh bare = quad("bare");
    UpdateMeshPositions part;
    part.mesh = "bare";
    part.offset = 1;
    part.tangents = std::vector<Vec4>{{0, 1, 0, 1}};
    apply_ok(*engine, bare);
    Error e = refused(*engine, part);
    EXPECT_EQ(e.field, "tangents");
    EXPECT_NE(e.message.find("has no tangents yet"), std::string::npos) << e.message;

    apply_ok(*engine, quad_with_tangents("q"), test::instance_edit("i", "q"));
    test::commit_ok(*engine);
    part.mesh = "q";
    part.offset = 2;
    part.tangents = std::vector<Vec4>{{0, 1, 0, -1}, {0, 1, 0, 1}};
    apply_ok(*engine, part);
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    std::vector<Vec4> want(4, Vec4(1, 0, 0, 1));
    want[2] = Vec4(0, 1, 0, -1);
    want[3] = Vec4(0, 1, 0, 1);
    EXPECT_EQ(tangents_of(*engine, "q"), want);

    // A refused batch leaves them; undo restores the previous ones.
    UpdateMeshPositions remove;
    remove.mesh = "q";
    remove.tangents = std::vector<Vec4>{};
    EditBatch b;
    b.edits.emplace_back(remove);
    b.edits.emplace_back(RemoveMesh{"no-such-mesh"});
    ASSERT_FALSE(engine->apply(std::move(b)).has_value());
    EXPECT_EQ(tangents_of(*engine, "q"), want);
    undo_last(*engine);
    EXPECT_EQ(tangents_of(*engine, "q"), std::vector<Vec4>(4, Vec4(1, 0, 0, 1)));
}

TEST(MeshTangents, ATopologyChangeOfTheVertexCountMustBringNewTangents) {
    auto engine = test::make_engine();
    apply_ok(*engine, quad_with_tangents("q"));
    ReplaceMeshTopology smaller;
    smaller.mesh = "q";
    smaller.positions = std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    smaller.triangles = {{0, 1, 2}};
    smaller.normals = std::vector<Vec3>(3, Vec3(0, 0, 1));
    smaller.uvs = std::vector<Vec2>(3, Vec2(0.5f));
    Error e = refused(*engine, smaller);
    EXPECT_EQ(e.field, "tangents");
    EXPECT_NE(e.message.find("needs new tangents"), std::string::npos) << e.message;
    smaller.tangents = std::vector<Vec4>{};
    apply_ok(*engine, smaller);
    EXPECT_TRUE(tangents_of(*engine, "q").empty());
    // Undo brings back the four vertices with their tangents, in one edit.
    undo_last(*engine);
    EXPECT_EQ(tangents_of(*engine, "q"), std::vector<Vec4>(4, Vec4(1, 0, 0, 1)));
}

TEST(MeshTangents, JournalCodecCarriesThemAsATaggedFieldOfEachMeshEdit) {
    // Without tangents, a mesh with normals and uvs is written exactly as before them.
    AddMesh plain = quad_with_tangents("q");
    plain.tangents.clear();
    EditBatch old;
    old.edits.emplace_back(plain);
    std::string old_bytes;
    durable::encode_batch(old, old_bytes);
    EXPECT_EQ(uint8_t(old_bytes[4]), 0x80u) << "extension bit only";

    EditBatch b;
    b.edits.emplace_back(quad_with_tangents("q"));
    UpdateMeshPositions u;
    u.mesh = "q";
    u.offset = 3;
    u.tangents = std::vector<Vec4>{{0, 1, 0, -1}};
    b.edits.emplace_back(u);
    ReplaceMeshTopology t;
    t.mesh = "q";
    t.triangles = {{0, 1, 2}};
    t.tangents = std::vector<Vec4>{};
    b.edits.emplace_back(t);
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(std::get<AddMesh>(back->edits[0]).tangents, quad_with_tangents("q").tangents);
    const auto& u2 = std::get<UpdateMeshPositions>(back->edits[1]);
    EXPECT_EQ(u2.tangents, u.tangents);
    EXPECT_FALSE(u2.normals.has_value());
    const auto& t2 = std::get<ReplaceMeshTopology>(back->edits[2]);
    ASSERT_TRUE(t2.tangents.has_value());
    EXPECT_TRUE(t2.tangents->empty());
    std::string again;
    durable::encode_batch(back.value(), again);
    EXPECT_EQ(again, bytes);
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(durable::decode_batch(std::string_view(bytes).substr(0, n)).has_value()) << n;

    // An add_mesh whose tangents tag holds none is not a form any writer produces.
    EditBatch empty;
    empty.edits.emplace_back(quad("e"));
    std::string forged;
    durable::encode_batch(empty, forged);
    forged[4] = char(0x40);  // tagged
    forged += std::string("\x01\x20", 2) + std::string(8, '\0');  // one field: tag 32, count 0
    auto refused_bytes = durable::decode_batch(forged);
    ASSERT_FALSE(refused_bytes.has_value());
    EXPECT_NE(refused_bytes.error().message.find("tangents"), std::string::npos)
        << refused_bytes.error().message;
}

TEST(MeshUvs1, TheSecondSetKeepsTheRulesOfTheFirstAndRoundTripsAsATaggedField) {
    auto engine = test::make_engine();
    AddMesh m = quad("q");
    m.uvs1 = {{0, 0}, {1, 0}, {0, std::nanf("")}, {1, 1}};
    Error e = refused(*engine, m);
    EXPECT_EQ(e.code, ErrorCode::NotFinite);
    EXPECT_EQ(e.field, "uvs1/5");
    m.uvs1.pop_back();
    EXPECT_EQ(refused(*engine, m).field, "uvs1");
    m.uvs1 = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    apply_ok(*engine, m);
    UpdateMeshPositions part;
    part.mesh = "q";
    part.offset = 3;
    part.uvs1 = std::vector<Vec2>{{0.5f, 0.5f}};
    apply_ok(*engine, part);
    const auto uvs1 = [&] {
        return engine->read([](const Scene& s) { return s.mesh(s.find_mesh("q")).value()->uvs1; });
    };
    EXPECT_EQ(uvs1()[3], Vec2(0.5f, 0.5f));
    undo_last(*engine);
    EXPECT_EQ(uvs1()[3], Vec2(1, 1));

    EditBatch b;
    b.edits.emplace_back(m);
    b.edits.emplace_back(part);
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(std::get<AddMesh>(back->edits[0]).uvs1, m.uvs1);
    EXPECT_EQ(std::get<UpdateMeshPositions>(back->edits[1]).uvs1, part.uvs1);
    std::string again;
    durable::encode_batch(back.value(), again);
    EXPECT_EQ(again, bytes);
}

}  // namespace
}  // namespace strata

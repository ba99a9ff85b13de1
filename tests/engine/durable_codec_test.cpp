// The journal's binary codec: CRC-32C known answers, edit batches that round-trip exactly, and
// damaged bytes that come back as errors, never as a crash or a huge allocation.

#include <string>

#include <gtest/gtest.h>

#include "engine/durable/crc32c.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/random_edits.h"

namespace strata {
namespace {

using durable::crc32c;

using test::encoded;

EditBatch every_kind() {
    EditBatch b;
    AddMesh m;
    m.id = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    m.build = {BuildPreference::FastBuild, false};
    m.material = "red";
    b.edits.emplace_back(AddMaterial{"red", Material{{1, 0, 0}, 0.25f, 0.5f, {0, 0, 0}}});
    b.edits.emplace_back(std::move(m));
    b.edits.emplace_back(UpdateMeshPositions{"tri", 1, {{2, 0, 0}}});
    b.edits.emplace_back(ReplaceMeshTopology{"tri", std::nullopt, {{0, 2, 1}}});
    b.edits.emplace_back(UpdateMaterial{"red", Vec3(0.5f), std::nullopt, 0.1f, std::nullopt});
    AddInstance i;
    i.id = "a";
    i.mesh = "tri";
    i.transform = Affine::translation({1, 2, 3});
    i.visible = false;
    i.mask = 6;
    i.user_id = 77;
    b.edits.emplace_back(i);
    UpdateInstance u;
    u.instance = "a";
    u.material = std::optional<std::string>();  // back to the mesh's material
    u.visible = true;
    b.edits.emplace_back(u);
    b.edits.emplace_back(SetTransform{"a", Affine::scaling({2, 2, 2})});
    b.edits.emplace_back(MarkDirty{std::nullopt, DirtyAction::Refit});
    b.edits.emplace_back(SetCamera{Vec3(1), std::nullopt, std::nullopt, 30.0f});
    b.edits.emplace_back(SetLighting{std::nullopt, Vec3(2), std::nullopt, 0.5f});
    b.edits.emplace_back(UpdateMeshVertices{"tri", {2, 0, 2}, {{0, 3, 0}, {0, 0, 1}, {0, 4, 0}}});
    b.edits.emplace_back(ReplaceMeshTriangles{"tri", 0, 1, {{0, 2, 1}, {1, 2, 0}}});
    b.edits.emplace_back(RemoveInstance{"a"});
    b.edits.emplace_back(RemoveMesh{"tri"});
    b.edits.emplace_back(RemoveMaterial{"red"});
    b.edits.emplace_back(Clear{});
    return b;
}

/// A batch with every kind and every field of the first layouts (before the field tables' tagged
/// fields), and the bytes the codec wrote for it then (generated at 5975336).
EditBatch first_layout_batch() {
    EditBatch b;
    AddMesh m;
    m.id = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    m.build = {BuildPreference::FastBuild, false};
    m.material = "red";
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    b.edits.emplace_back(AddTexture{"tex", "bytes"});
    AddMaterial am{"red", Material{{1, 0, 0}, 0.25f, 0.5f, {0, 0, 0}}};
    am.textures[0] = "tex";
    am.material.base_color_sampler.wrap = TextureWrap::Mirror;
    b.edits.emplace_back(am);
    b.edits.emplace_back(std::move(m));
    b.edits.emplace_back(UpdateMeshPositions{"tri", 1, {{2, 0, 0}}});
    b.edits.emplace_back(ReplaceMeshTopology{"tri", std::nullopt, {{0, 2, 1}}});
    UpdateMaterial um{"red", Vec3(0.5f), std::nullopt, 0.1f, std::nullopt};
    um.filter = TextureFilter::Nearest;
    b.edits.emplace_back(um);
    b.edits.emplace_back(AddGroup{"g", std::nullopt, Affine::translation({0, 1, 0}), false});
    UpdateGroup ug;
    ug.group = "g";
    ug.visible = true;
    ug.transform = Affine::scaling({2, 2, 2});
    b.edits.emplace_back(ug);
    AddInstance i;
    i.id = "a";
    i.mesh = "tri";
    i.transform = Affine::translation({1, 2, 3});
    i.visible = false;
    i.mask = 6;
    i.user_id = 77;
    i.parent = "g";
    b.edits.emplace_back(i);
    UpdateInstance u;
    u.instance = "a";
    u.material = std::optional<std::string>();
    u.visible = true;
    u.mask = 3;
    b.edits.emplace_back(u);
    b.edits.emplace_back(SetTransform{"a", Affine::scaling({2, 2, 2})});
    b.edits.emplace_back(MarkDirty{std::nullopt, DirtyAction::Refit});
    b.edits.emplace_back(SetCamera{Vec3(1), std::nullopt, std::nullopt, 30.0f});
    b.edits.emplace_back(SetLighting{std::nullopt, Vec3(2), std::nullopt, 0.5f});
    Light l;
    l.kind = LightKind::Spot;
    l.intensity = 40;
    b.edits.emplace_back(AddLight{"lamp", l});
    UpdateLight ul;
    ul.light = "lamp";
    ul.inner_angle_deg = 20;
    ul.kind = LightKind::Rect;
    b.edits.emplace_back(ul);
    b.edits.emplace_back(RemoveLight{"lamp"});
    b.edits.emplace_back(RemoveGroup{"g", true});
    b.edits.emplace_back(RemoveInstance{"a"});
    b.edits.emplace_back(RemoveMesh{"tri"});
    b.edits.emplace_back(RemoveTexture{"tex"});
    b.edits.emplace_back(Clear{});
    return b;
}

constexpr const char* FIRST_LAYOUT_HEX =
    "1600000014030000007465780500000062797465738403000000726564000080"
    "3f00000000000000000000803e0000003f000000000000000000000000010300"
    "0000746578020080030000007472690300000000000000000000000000000000"
    "0000000000803f0000000000000000000000000000803f000000000100000000"
    "0000000000000001000000020000000100010300000072656403000000000000"
    "0000000000000000000000803f00000000000000000000803f00000000000000"
    "000000803f000000000000000001030000007472690100000001000000000000"
    "0000000040000000000000000002030000007472690001000000000000000000"
    "000002000000010000008503000000726564010000003f0000003f0000003f00"
    "01cdcccc3d00000001010e0100000067000000803f0000000000000000000000"
    "00000000000000803f000000000000803f00000000000000000000803f000000"
    "00000f0100000067000100000040000000000000000000000000000000000000"
    "0040000000000000000000000000000000000000004000000000010186010000"
    "006103000000747269000000803f00000000000000000000803f000000000000"
    "803f000000000000004000000000000000000000803f0000404000060000004d"
    "0000000101000000670701000000610100000101010300000000080100000061"
    "0000004000000000000000000000000000000000000000400000000000000000"
    "000000000000000000000040000000000a00000b010000803f0000803f000080"
    "3f0000010000f0410c000100000040000000400000004000010000003f110400"
    "00006c616d700100000000000040400000000000000000000080bf0000000000"
    "00803f0000803f0000803f000020420000f0410000c8410000803f0000803f12"
    "040000006c616d7001020000000000010000a041000013040000006c616d7010"
    "010000006701090100000061030300000074726915030000007465780d";

std::string from_hex(std::string_view hex) {
    std::string out;
    for (std::size_t i = 0; i + 1 < hex.size(); i += 2)
        out += char(std::stoi(std::string(hex.substr(i, 2)), nullptr, 16));
    return out;
}

TEST(EditCodec, FilesWrittenBeforeTheFieldTablesReadAndWriteTheSame) {
    const std::string old_bytes = from_hex(FIRST_LAYOUT_HEX);
    EXPECT_EQ(encoded(first_layout_batch()), old_bytes);
    auto back = durable::decode_batch(old_bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(encoded(back.value()), old_bytes);
}

TEST(Crc32c, MatchesTheCastagnoliCheckValue) {
    EXPECT_EQ(crc32c("123456789", 9), 0xE3069283u);
    EXPECT_EQ(crc32c("", 0), 0u);
}

TEST(Crc32c, ExtendingInPiecesEqualsOnePass) {
    std::string data;
    for (int i = 0; i < 1000; ++i) data.push_back(char(i * 31));
    for (std::size_t cut : {0u, 1u, 7u, 8u, 9u, 500u, 999u})
        EXPECT_EQ(crc32c(data.data() + cut, data.size() - cut, crc32c(data.data(), cut)),
                  crc32c(data.data(), data.size()))
            << cut;
}

TEST(EditCodec, EveryEditKindRoundTripsByteForByte) {
    const EditBatch b = every_kind();
    const std::string bytes = encoded(b);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    ASSERT_EQ(back->edits.size(), b.edits.size());
    for (std::size_t i = 0; i < b.edits.size(); ++i)
        EXPECT_EQ(back->edits[i].index(), b.edits[i].index()) << i;
    EXPECT_EQ(encoded(back.value()), bytes);
    const auto& inst = std::get<AddInstance>(back->edits[5]);
    EXPECT_EQ(inst.mask, 6u);
    EXPECT_EQ(inst.user_id, 77u);
    EXPECT_FALSE(inst.visible);
    EXPECT_EQ(inst.transform.m, Affine::translation({1, 2, 3}).m);
    const auto& upd = std::get<UpdateInstance>(back->edits[6]);
    ASSERT_TRUE(upd.material.has_value());
    EXPECT_FALSE(upd.material->has_value());
    const auto& listed = std::get<UpdateMeshVertices>(back->edits[11]);
    EXPECT_EQ(listed.vertices, (std::vector<uint32_t>{2, 0, 2}));
    EXPECT_EQ(listed.positions[2], Vec3(0, 4, 0));
    const auto& spliced = std::get<ReplaceMeshTriangles>(back->edits[12]);
    EXPECT_EQ(spliced.first, 0u);
    EXPECT_EQ(spliced.count, 1u);
    EXPECT_EQ(spliced.triangles, (std::vector<Triangle>{{0, 2, 1}, {1, 2, 0}}));
}

TEST(EditCodec, GroupEditsAndParentsRoundTrip) {
    EditBatch b;
    b.edits.emplace_back(AddGroup{"car", std::nullopt, Affine::translation({1, 2, 3}), false});
    b.edits.emplace_back(AddGroup{"wheels", std::string("car"), Affine::scaling({2, 2, 2}), true});
    AddInstance inside;
    inside.id = "w0";
    inside.mesh = "tri";
    inside.parent = "wheels";
    b.edits.emplace_back(inside);
    UpdateInstance to_root;
    to_root.instance = "w0";
    to_root.parent = std::optional<std::string>();
    b.edits.emplace_back(to_root);
    UpdateInstance to_group;
    to_group.instance = "w0";
    to_group.parent = std::optional<std::string>("car");
    to_group.mask = 3;
    b.edits.emplace_back(to_group);
    b.edits.emplace_back(UpdateGroup{"wheels", std::optional<std::string>(), std::nullopt, false});
    b.edits.emplace_back(UpdateGroup{"car", std::nullopt, Affine::translation({0, 1, 0}), std::nullopt});
    b.edits.emplace_back(RemoveGroup{"car", true});
    const std::string bytes = encoded(b);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(encoded(back.value()), bytes);
    const auto& car = std::get<AddGroup>(back->edits[0]);
    EXPECT_FALSE(car.parent.has_value());
    EXPECT_FALSE(car.visible);
    EXPECT_EQ(car.transform, Affine::translation({1, 2, 3}));
    EXPECT_EQ(std::get<AddGroup>(back->edits[1]).parent, std::optional<std::string>("car"));
    EXPECT_EQ(std::get<AddInstance>(back->edits[2]).parent, std::optional<std::string>("wheels"));
    const auto& root = std::get<UpdateInstance>(back->edits[3]);
    ASSERT_TRUE(root.parent.has_value());
    EXPECT_FALSE(root.parent->has_value());
    const auto& moved = std::get<UpdateInstance>(back->edits[4]);
    EXPECT_EQ(*moved.parent, std::optional<std::string>("car"));
    EXPECT_EQ(moved.mask, std::optional<uint32_t>(3));
    const auto& wheels = std::get<UpdateGroup>(back->edits[5]);
    ASSERT_TRUE(wheels.parent.has_value());
    EXPECT_FALSE(wheels.parent->has_value());
    EXPECT_EQ(wheels.visible, std::optional<bool>(false));
    EXPECT_TRUE(std::get<RemoveGroup>(back->edits[7]).recursive);
}

TEST(EditCodec, AGroupsAssetFieldRoundTripsBesideItsName) {
    EditBatch b;
    AddGroup kit{"kit", std::nullopt, Affine::identity(), true};
    kit.asset = "kit.tar";
    kit.name = "Kit";
    b.edits.emplace_back(kit);
    UpdateGroup unmark;
    unmark.group = "kit";
    unmark.asset = "";
    b.edits.emplace_back(unmark);
    const std::string bytes = encoded(b);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(encoded(back.value()), bytes);
    EXPECT_EQ(std::get<AddGroup>(back->edits[0]).asset, "kit.tar");
    EXPECT_EQ(std::get<AddGroup>(back->edits[0]).name, "Kit");
    EXPECT_EQ(std::get<UpdateGroup>(back->edits[1]).asset, std::optional<std::string>(""));
    EXPECT_FALSE(std::get<UpdateGroup>(back->edits[1]).name.has_value());
    // An empty asset field costs nothing in the record (the test of files written before the
    // field tables holds the old bytes).
    EditBatch plain;
    plain.edits.emplace_back(AddGroup{"kit", std::nullopt, Affine::identity(), true});
    EditBatch marked = plain;
    std::get<AddGroup>(marked.edits[0]).asset = "kit.tar";
    EXPECT_LT(encoded(plain).size(), encoded(marked).size());
}

TEST(EditCodec, AnInstanceWithoutAParentIsWrittenAsBeforeGroups) {
    // Journals written before groups existed hold tag 6 with the older layout; an add_instance
    // without a parent must still be exactly that, and one with a parent must not be.
    AddInstance e;
    e.id = "a";
    e.mesh = "m";
    const std::string plain = encoded(EditBatch{{e}});
    EXPECT_EQ(uint8_t(plain[4]), 6u);
    e.parent = "g";
    const std::string with_parent = encoded(EditBatch{{e}});
    EXPECT_NE(uint8_t(with_parent[4]), 6u);
    EXPECT_EQ(with_parent.substr(5, plain.size() - 5), plain.substr(5));
}

TEST(EditCodec, BuildFlagsTakeTheOldRefitByteAndUnknownBitsAreRefused) {
    // allow_refit was a bool byte: compaction is its second bit, so files written before it
    // read unchanged (FilesWrittenBeforeTheFieldTablesReadAndWriteTheSame) and a mesh without
    // compaction is written exactly as before.
    AddMesh e;
    e.id = "m";
    e.positions = {Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    e.triangles = {Triangle(0, 1, 2)};
    e.build.allow_refit = false;
    const std::string plain = encoded(EditBatch{{e}});
    e.build.compact = true;
    const std::string compact = encoded(EditBatch{{e}});
    ASSERT_EQ(plain.size(), compact.size());
    std::size_t differ = 0, at = 0;
    for (std::size_t i = 0; i < plain.size(); ++i) {
        if (plain[i] != compact[i]) ++differ, at = i;
    }
    ASSERT_EQ(differ, 1u);
    EXPECT_EQ(uint8_t(plain[at]), 0u);
    EXPECT_EQ(uint8_t(compact[at]), 2u);
    auto back = durable::decode_batch(compact);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    const BuildOptions& b = std::get<AddMesh>(back->edits[0]).build;
    EXPECT_TRUE(b.compact);
    EXPECT_FALSE(b.allow_refit);

    std::string unknown = compact;
    unknown[at] = char(6);
    auto refused = durable::decode_batch(unknown);
    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().message.find("build flags byte 6"), std::string::npos)
        << refused.error().message;
}

TEST(EditCodec, RandomBatchesRoundTrip) {
    test::RandomEdits edits(1234);
    for (int i = 0; i < 200; ++i) {
        const EditBatch b = i == 0 ? edits.initial_batch(4, 20) : edits.next_batch(8);
        const std::string bytes = encoded(b);
        auto back = durable::decode_batch(bytes);
        ASSERT_TRUE(back.has_value()) << back.error().describe();
        EXPECT_EQ(encoded(back.value()), bytes) << "batch " << i;
    }
}

TEST(EditCodec, MeshArraysAreRawLittleEndianBuffers) {
    EditBatch b;
    b.edits.emplace_back(UpdateMeshPositions{"m", 0, {{1.0f, 2.0f, 3.0f}}});
    const std::string bytes = encoded(b);
    // count, tag, id length, id, offset, element count, then three floats as they are in memory.
    const float want[3] = {1.0f, 2.0f, 3.0f};
    ASSERT_EQ(bytes.size(), 4u + 1 + 4 + 1 + 4 + 8 + 12);
    EXPECT_EQ(bytes.substr(bytes.size() - 12),
              std::string(reinterpret_cast<const char*>(want), 12));
}

TEST(EditCodec, EveryTruncationIsAnErrorNotACrash) {
    const std::string bytes = encoded(every_kind());
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        auto back = durable::decode_batch(std::string_view(bytes).substr(0, n));
        ASSERT_FALSE(back.has_value()) << "prefix of " << n << " bytes decoded";
        EXPECT_EQ(back.error().code, ErrorCode::InvalidArgument);
    }
}

TEST(EditCodec, AHugeCorruptCountIsRefusedBeforeAllocating) {
    std::string bytes = encoded(every_kind());
    // The top bit says the batch's info follows (edit_codec.h): the largest count is below it.
    bytes[0] = bytes[1] = bytes[2] = char(0xFF);
    bytes[3] = char(0x7F);
    auto back = durable::decode_batch(bytes);
    ASSERT_FALSE(back.has_value());
    EXPECT_NE(back.error().message.find("edit count"), std::string::npos) << back.error().message;
    bytes[3] = char(0xFF);
    EXPECT_FALSE(durable::decode_batch(bytes).has_value());
}

TEST(EditCodec, AnUnknownKindIsNamed) {
    std::string bytes = encoded(every_kind());
    bytes[4] = char(59);
    auto back = durable::decode_batch(bytes);
    ASSERT_FALSE(back.has_value());
    EXPECT_NE(back.error().message.find("unknown edit kind 59"), std::string::npos)
        << back.error().message;
}

TEST(EditCodec, AnExtensionBitWithNothingToExtendIsRefused) {
    // Found by journal_record_fuzzer: a set_camera tag with the extension bit decoded, then
    // re-encoded without it. Every decodable form must be the one the encoder writes.
    const std::string found("\x01\x00\x00\x00\x8b\x01\xf8\x00\x60\x63\x00\x3f\x60\x00\x00"
                            "\x00\x80\x3f\x00\x00\x01\x00\x00\xf0\x41",
                            25);
    auto back = durable::decode_batch(found);
    ASSERT_FALSE(back.has_value()) << "decoded to " << encoded(back.value()).size() << " bytes";
    EXPECT_NE(back.error().message.find("extension bit"), std::string::npos)
        << back.error().message;
    EXPECT_NE(back.error().message.find("set_camera"), std::string::npos) << back.error().message;

    // The same for every kind written without the bit: setting it never decodes.
    for (const Edit& edit : every_kind().edits) {
        std::string bytes = encoded(EditBatch{{edit}});
        ASSERT_EQ(uint8_t(bytes[4]) & 0x80u, 0u);
        bytes[4] = char(uint8_t(bytes[4]) | 0x80u);
        EXPECT_FALSE(durable::decode_batch(bytes).has_value()) << "kind " << edit.index();
    }
}

TEST(EditCodec, TaggedFieldsOutOfTheWritersOrderAreRefused) {
    // Found by journal_record_fuzzer: an update_instance whose tagged fields came as motion,
    // animation, lod_far decoded, then re-encoded in table order (motion, lod_far, animation).
    UpdateInstance u;
    u.instance = "a";
    u.lod_far = 3.0f;
    u.animation = std::vector<Keyframe>{{0.0f, Affine{}}, {1.5f, Affine::translation({1, 2, 3})}};
    const std::string written = encoded(EditBatch{{u}});
    ASSERT_TRUE(durable::decode_batch(written).has_value());
    // Swap the two tagged fields: [count][4][float][6][u64 count][2 keys] -> [6]...[4][float].
    const std::size_t section = written.size() - (2 + 4 + 1 + 8 + 2 * sizeof(Keyframe));
    ASSERT_EQ(uint8_t(written[section]), 2u);
    ASSERT_EQ(uint8_t(written[section + 1]), 4u);
    const std::string lod = written.substr(section + 1, 5);
    const std::string animation = written.substr(section + 6);
    const std::string swapped = written.substr(0, section + 1) + animation + lod;
    auto back = durable::decode_batch(swapped);
    ASSERT_FALSE(back.has_value()) << "decoded to " << encoded(back.value()).size() << " bytes";
    EXPECT_NE(back.error().message.find("field tag 4 twice or out of order"), std::string::npos)
        << back.error().message;
}

TEST(JournalFormat, ATornRecordAtTheEndIsToldFromDamageInTheMiddle) {
    std::string file = durable::segment_header(0);
    std::vector<std::size_t> starts;
    for (uint64_t v = 1; v <= 3; ++v) {
        auto r = durable::prepare_record(every_kind());
        durable::stamp_record(r, v);
        starts.push_back(file.size());
        file += r.bytes;
    }
    auto clean = durable::scan_segment(file);
    EXPECT_EQ(clean.tail, durable::SegmentScan::Tail::Clean);
    EXPECT_EQ(clean.records.size(), 3u);

    auto torn = durable::scan_segment(std::string_view(file).substr(0, file.size() - 5));
    EXPECT_EQ(torn.tail, durable::SegmentScan::Tail::Torn);
    EXPECT_EQ(torn.records.size(), 2u);
    EXPECT_EQ(torn.valid_end, starts[2]);

    std::string flipped = file;
    flipped[starts[1] + 40] ^= 0x10;
    auto corrupt = durable::scan_segment(flipped);
    EXPECT_EQ(corrupt.tail, durable::SegmentScan::Tail::Corrupt);
    EXPECT_EQ(corrupt.records.size(), 1u);
    EXPECT_NE(corrupt.problem.find("offset " + std::to_string(starts[1])), std::string::npos)
        << corrupt.problem;
}

TEST(SnapshotFormat, RoundTripsAndRefusesDamage) {
    const std::string bytes = durable::encode_snapshot(every_kind(), 42);
    auto back = durable::decode_snapshot(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(back->version, 42u);
    EXPECT_EQ(encoded(back->scene), encoded(every_kind()));
    std::string damaged = bytes;
    damaged[bytes.size() / 2] ^= 1;
    EXPECT_FALSE(durable::decode_snapshot(damaged).has_value());
    EXPECT_FALSE(durable::decode_snapshot(bytes.substr(0, bytes.size() - 1)).has_value());
    EXPECT_FALSE(durable::decode_snapshot("hello").has_value());
}

}  // namespace
}  // namespace strata

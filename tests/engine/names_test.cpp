// The `name` field that every object kind has, landed through the field tables alone: it is kept
// by apply, undone with its batch, carried by snapshots and the journal, reported by picks, and
// held to the text rule on every way in.

#include <string>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/scene/scene.h"
#include "engine/scene/shapes.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using test::encoded;

/// One named object of every kind.
EditBatch named_scene() {
    EditBatch b;
    AddTexture t{"t", test::png_bytes(1, 1, {10, 20, 30})};
    t.name = "Brick texture";
    b.edits.emplace_back(std::move(t));
    AddMaterial m{"m", Material{}};
    m.material.name = "Rough red";
    b.edits.emplace_back(std::move(m));
    AddMesh mesh = add_mesh_edit("tri", make_box(Vec3(1)));
    mesh.name = "Crate \xc3\xa9";  // UTF-8 is welcome
    b.edits.emplace_back(std::move(mesh));
    AddGroup g;
    g.id = "g";
    g.name = "Left wing";
    b.edits.emplace_back(std::move(g));
    AddInstance i;
    i.id = "i";
    i.mesh = "tri";
    i.parent = "g";
    i.name = "Crate #1";
    b.edits.emplace_back(std::move(i));
    Light l;
    l.name = "Key light";
    b.edits.emplace_back(AddLight{"l", l});
    return b;
}

void expect_names(const Scene& s) {
    EXPECT_EQ(s.texture(s.find_texture("t")).value()->name, "Brick texture");
    EXPECT_EQ(s.material(s.find_material("m")).value()->material.name, "Rough red");
    EXPECT_EQ(s.mesh(s.find_mesh("tri")).value()->name, "Crate \xc3\xa9");
    EXPECT_EQ(s.group(s.find_group("g")).value()->name, "Left wing");
    EXPECT_EQ(s.instance(s.find_instance("i")).value()->rare->name, "Crate #1");
    EXPECT_EQ(s.lights().get(s.find_light("l"))->light.name, "Key light");
}

TEST(Names, EveryKindKeepsItsNameThroughApplyAndTheSnapshotBatch) {
    Scene s;
    ASSERT_TRUE(s.apply(named_scene()).has_value());
    expect_names(s);
    // A snapshot is the scene's rebuild batch in the journal's codec.
    auto back = durable::decode_batch(encoded(s.to_batch()));
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    Scene restored;
    ASSERT_TRUE(restored.apply(std::move(back).value()).has_value());
    expect_names(restored);
}

TEST(Names, ARenameIsUndoneWithItsBatch) {
    Scene s;
    ASSERT_TRUE(s.apply(named_scene()).has_value());
    EditBatch b;
    UpdateInstance ui;
    ui.instance = "i";
    ui.name = "renamed";
    b.edits.emplace_back(ui);
    UpdateGroup ug;
    ug.group = "g";
    ug.name = "renamed";
    b.edits.emplace_back(ug);
    UpdateLight ul;
    ul.light = "l";
    ul.name = "renamed";
    b.edits.emplace_back(ul);
    UpdateMaterial um;
    um.material = "m";
    um.name = "renamed";
    b.edits.emplace_back(um);
    b.edits.emplace_back(RemoveMesh{"nope"});  // refused: the whole batch is undone
    ASSERT_FALSE(s.apply(std::move(b)).has_value());
    expect_names(s);

    s.clear_changes();
    UpdateInstance rename;
    rename.instance = "i";
    rename.name = "Crate #2";
    ASSERT_TRUE(s.apply(EditBatch{{rename}}).has_value());
    EXPECT_EQ(s.instance(s.find_instance("i")).value()->rare->name, "Crate #2");
    // A rename is no acceleration work: nothing is marked for the commit.
    EXPECT_TRUE(s.changes().instances().empty());
}

TEST(Names, ANameBreakingTheTextRuleIsRefusedOnEveryWayIn) {
    for (const std::string& bad : {std::string("m\xff"), std::string("two\nlines"),
                                   std::string("esc\x1b[31m"), std::string(1025, 'x')}) {
        SCOPED_TRACE(bad.size() > 20 ? "long name" : bad);
        // Straight into apply, as the JSON parser hands it on.
        Scene s;
        EditBatch b = named_scene();
        std::get<AddInstance>(b.edits[4]).name = bad;
        auto applied = s.apply(std::move(b));
        ASSERT_FALSE(applied.has_value());
        EXPECT_EQ(applied.error().code, ErrorCode::InvalidArgument);
        EXPECT_EQ(applied.error().field, "name");
        EXPECT_EQ(applied.error().edit_index, 4u);
        EXPECT_EQ(s.counts().meshes, 0u) << "a refused batch changes nothing";

        // Through the codec, as a journal record, a replicated record or a snapshot arrives.
        EditBatch again = named_scene();
        std::get<AddLight>(again.edits[5]).light.name = bad;
        auto decoded = durable::decode_batch(encoded(again));
        ASSERT_TRUE(decoded.has_value());
        Scene loaded;
        Status first_refusal;
        for (Edit& e : decoded.value().edits) {
            if (Status st = loaded.load(std::move(e)); !st) {
                first_refusal = st;
                break;
            }
        }
        ASSERT_FALSE(first_refusal.has_value());
        EXPECT_EQ(first_refusal.error().field, "name");
    }
}

TEST(Names, AnUnnamedEditIsWrittenAsBeforeNamesAndANamedOneInTheTaggedSection) {
    AddInstance e;
    e.id = "a";
    e.mesh = "m";
    const std::string plain = encoded(EditBatch{{e}});
    EXPECT_EQ(uint8_t(plain[4]), 6u);
    e.name = "n";
    const std::string named = encoded(EditBatch{{e}});
    EXPECT_EQ(uint8_t(named[4]), 6u | 0x40u);
    // The first layout, then the count, the tag and the text.
    EXPECT_EQ(named.substr(5, plain.size() - 5), plain.substr(5));
    EXPECT_EQ(named.substr(plain.size()), std::string("\x01\x01\x01\x00\x00\x00n", 7));
}

TEST(Names, DamagedTaggedSectionsAreRefusedNotGuessed) {
    AddInstance e;
    e.id = "a";
    e.mesh = "m";
    e.name = "n";
    const std::string named = encoded(EditBatch{{e}});
    const std::size_t section = named.size() - 7;
    const auto refused = [](std::string bytes, const char* why) {
        auto back = durable::decode_batch(bytes);
        ASSERT_FALSE(back.has_value()) << why;
        EXPECT_NE(back.error().message.find(why), std::string::npos) << back.error().message;
    };
    std::string unknown = named;
    unknown[section + 1] = char(9);
    refused(unknown, "unknown field tag 9");
    std::string twice = named.substr(0, section) + "\x02" + named.substr(section + 1) +
                        named.substr(section + 1);
    refused(twice, "field tag 1 twice");
    std::string empty_name = named.substr(0, section) + std::string("\x01\x01\x00\x00\x00\x00", 6);
    refused(empty_name, "holds its default");
    std::string empty_section = named.substr(0, section) + std::string("\x00", 1);
    refused(empty_section, "empty tagged section");
    // The bit on a kind whose edits carry no fields (remove_instance).
    std::string no_table = encoded(EditBatch{{RemoveInstance{"a"}}});
    no_table[4] = char(uint8_t(no_table[4]) | 0x40u);
    refused(no_table + std::string("\x01\x01\x00\x00\x00\x00", 6), "tagged fields on an edit");
}

}  // namespace
}  // namespace strata

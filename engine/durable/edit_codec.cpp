#include "engine/durable/edit_codec.h"

#include <concepts>
#include <cstring>
#include <iterator>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

#include "engine/durable/byte_io.h"

namespace strata::durable {

namespace {

// The kind tag is the Edit variant's index; files written today must read back tomorrow, so the
// order of the variant is pinned here. A new kind goes at the end.
template <std::size_t I, class T>
constexpr bool TAG_IS = std::is_same_v<std::variant_alternative_t<I, Edit>, T>;
static_assert(TAG_IS<0, AddMesh> && TAG_IS<1, UpdateMeshPositions> &&
                  TAG_IS<2, ReplaceMeshTopology> && TAG_IS<3, RemoveMesh> &&
                  TAG_IS<4, AddMaterial> && TAG_IS<5, UpdateMaterial> && TAG_IS<6, AddInstance> &&
                  TAG_IS<7, UpdateInstance> && TAG_IS<8, SetTransform> &&
                  TAG_IS<9, RemoveInstance> && TAG_IS<10, MarkDirty> && TAG_IS<11, SetCamera> &&
                  TAG_IS<12, SetLighting> && TAG_IS<13, Clear> && TAG_IS<14, AddGroup> &&
                  TAG_IS<15, UpdateGroup> && TAG_IS<16, RemoveGroup> && TAG_IS<17, AddLight> &&
                  TAG_IS<18, UpdateLight> && TAG_IS<19, RemoveLight> &&
                  TAG_IS<20, AddTexture> && TAG_IS<21, RemoveTexture> &&
                  TAG_IS<22, UpdateMeshVertices> && TAG_IS<23, RemoveMaterial> &&
                  TAG_IS<24, AddInstances> && TAG_IS<25, UpdateInstances> &&
                  TAG_IS<26, RemoveInstances> && TAG_IS<27, ReplaceMeshTriangles> &&
                  TAG_IS<28, SetTime> && std::variant_size_v<Edit> == 29,
              "journal kind tags are the Edit variant's indices: append new kinds at the end");


/// Kind names for messages (the wire names, as the protocol's op table spells them).
constexpr const char* KIND_NAMES[] = {"add_mesh",
                                      "update_mesh_positions",
                                      "replace_mesh_topology",
                                      "remove_mesh",
                                      "add_material",
                                      "update_material",
                                      "add_instance",
                                      "update_instance",
                                      "set_transform",
                                      "remove_instance",
                                      "mark_dirty",
                                      "set_camera",
                                      "set_lighting",
                                      "clear",
                                      "add_group",
                                      "update_group",
                                      "remove_group",
                                      "add_light",
                                      "update_light",
                                      "remove_light",
                                      "add_texture",
                                      "remove_texture",
                                      "update_mesh_vertices",
                                      "remove_material",
                                      "add_instances",
                                      "update_instances",
                                      "remove_instances",
                                      "replace_triangles",
                                      "set_time"};
static_assert(std::size(KIND_NAMES) == std::variant_size_v<Edit>);

/// Kind tag bit: the edit's extension fields follow its base layout. Fields added to a kind after
/// its layout was first written (a mesh's normals and uvs, an instance's parent group) are
/// extensions: an edit without them is written exactly as before, so older files read the same
/// and a file only grows the bit where it uses what is new.
constexpr uint8_t EXTENDED = 0x80;
/// Kind tag bit: the edit's tagged fields follow (after its extension fields, if any): fields
/// added to a kind's table after its first layout (tag > 0 in object_fields.h), and a few outside
/// the tables (a material's texture slots, a mesh's later vertex attributes), written as a count
/// byte, then a tag byte and the value for each field that is not absent.
constexpr uint8_t TAGGED = 0x40;
static_assert(std::variant_size_v<Edit> < TAGGED);

// Step: one layout per edit kind -----------------------------------------------------------------

template <class Io, Kind<AddMesh> E>
void fields(Io& io, E& e) {
    io(e.id, e.positions, e.triangles, e.build, e.material);
}
template <class Io, Kind<UpdateMeshPositions> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.offset, e.positions);
}
template <class Io, Kind<UpdateMeshVertices> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.vertices, e.positions);
}
template <class Io, Kind<ReplaceMeshTopology> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.positions, e.triangles);
}
template <class Io, Kind<ReplaceMeshTriangles> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.first, e.count, e.triangles);
}
template <class Io, Kind<RemoveMesh> E>
void fields(Io& io, E& e) {
    io(e.mesh);
}
template <class Io, Kind<AddMaterial> E>
void fields(Io& io, E& e) {
    io(e.id, e.material);
}
template <class Io, Kind<RemoveMaterial> E>
void fields(Io& io, E& e) {
    io(e.material);
}
template <class Io, Kind<UpdateMaterial> E>
void fields(Io& io, E& e) {
    io(e.material);
    table_updates<MaterialFields>(io, e);
}
template <class Io, Kind<AddInstance> E>
void fields(Io& io, E& e) {
    io(e.id, e.mesh, e.material);
    table_fields<InstanceFields>(io, e);
}
template <class Io, Kind<UpdateInstance> E>
void fields(Io& io, E& e) {
    io(e.instance, e.material);
    table_updates<InstanceFields>(io, e);
}
template <class Io, Kind<SetTransform> E>
void fields(Io& io, E& e) {
    io(e.instance, e.transform);
}
template <class Io, Kind<RemoveInstance> E>
void fields(Io& io, E& e) {
    io(e.instance);
}
/// Bulk edits store their arrays as they came: the id list or range, then one value or one per
/// item.
template <class Io, Kind<BulkIds> E>
void ids_fields(Io& io, E& ids) {
    io(ids.list, ids.prefix, ids.first, ids.count);
}
template <class Io, Kind<AddInstances> E>
void fields(Io& io, E& e) {
    ids_fields(io, e.ids);
    io(e.meshes, e.materials, e.transforms, e.parent, e.visible);
}
template <class Io, Kind<UpdateInstances> E>
void fields(Io& io, E& e) {
    ids_fields(io, e.ids);
    io(e.transforms, e.visible);
}
template <class Io, Kind<RemoveInstances> E>
void fields(Io& io, E& e) {
    ids_fields(io, e.ids);
}
template <class Io, Kind<MarkDirty> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.action);
}
template <class Io, Kind<SetCamera> E>
void fields(Io& io, E& e) {
    table_updates<CameraFields>(io, e);
}
template <class Io, Kind<SetLighting> E>
void fields(Io& io, E& e) {
    table_updates<LightingFields>(io, e);
}
template <class Io, Kind<SetTime> E>
void fields(Io& io, E& e) {
    table_updates<TimelineFields>(io, e);
}
template <class Io, Kind<Clear> E>
void fields(Io&, E&) {}
template <class Io, Kind<AddGroup> E>
void fields(Io& io, E& e) {
    io(e.id, e.parent);
    table_fields<GroupFields>(io, e);
}
template <class Io, Kind<UpdateGroup> E>
void fields(Io& io, E& e) {
    io(e.group, e.parent);
    table_updates<GroupFields>(io, e);
}
template <class Io, Kind<RemoveGroup> E>
void fields(Io& io, E& e) {
    io(e.group, e.recursive);
}
template <class Io, Kind<AddTexture> E>
void fields(Io& io, E& e) {
    io(e.id, e.data);
}
template <class Io, Kind<RemoveTexture> E>
void fields(Io& io, E& e) {
    io(e.texture);
}

template <class Io, Kind<AddLight> E>
void fields(Io& io, E& e) {
    io(e.id, e.light);
}
template <class Io, Kind<UpdateLight> E>
void fields(Io& io, E& e) {
    io(e.light);
    table_updates<LightFields>(io, e);
}
template <class Io, Kind<RemoveLight> E>
void fields(Io& io, E& e) {
    io(e.light);
}

// Step: extension fields of the kinds that have them -------------------------------------------

template <class Io, class E>
void extension(Io&, E&) {}
template <class Io, Kind<AddMesh> E>
void extension(Io& io, E& e) {
    io(e.normals, e.uvs);
}
template <class Io, Kind<UpdateMeshPositions> E>
void extension(Io& io, E& e) {
    io(e.normals, e.uvs);
}
template <class Io, Kind<ReplaceMeshTopology> E>
void extension(Io& io, E& e) {
    io(e.normals, e.uvs);
}

template <class Io, Kind<AddInstance> E>
void extension(Io& io, E& e) {
    io(e.parent);
}
/// A material's texture and its sampler.
template <class Io, Kind<AddMaterial> E>
void extension(Io& io, E& e) {
    io(e.textures[slot_index(TextureSlot::BaseColor)], e.material.base_color_sampler.wrap,
       e.material.base_color_sampler.filter);
}
/// update_material's texture is "unchanged" (absent), "none" (null) or a texture id, like
/// update_instance's parent; the sampler fields are plain optionals.
template <class Io, Kind<UpdateMaterial> E>
void extension(Io& io, E& e) {
    auto& base = e.textures[slot_index(TextureSlot::BaseColor)];
    if constexpr (std::is_const_v<E>) {
        io(base.has_value());
        if (base) io(*base);
    } else {
        bool set = false;
        io(set);
        if (set) {
            std::optional<std::string> texture;
            io(texture);
            base = std::move(texture);
        }
    }
    io(e.wrap, e.filter);
}
/// update_instance's parent is "unchanged" (absent), "the root" (null) or a group: only a present
/// parent is an extension, written as the optional group id.
template <class Io, Kind<UpdateInstance> E>
void extension(Io& io, E& e) {
    if constexpr (std::is_const_v<E>) {
        io(*e.parent);
    } else {
        std::optional<std::string> parent;
        io(parent);
        e.parent = std::move(parent);
    }
}

template <class E>
bool has_extension(const E&) {
    return false;
}
bool has_extension(const AddMesh& e) {
    return !e.normals.empty() || !e.uvs.empty();
}
bool has_extension(const UpdateMeshPositions& e) {
    return e.normals || e.uvs;
}
bool has_extension(const ReplaceMeshTopology& e) {
    return e.normals || e.uvs;
}
bool has_extension(const AddInstance& e) {
    return e.parent.has_value();
}
bool has_extension(const UpdateInstance& e) {
    return e.parent.has_value();
}
bool has_extension(const AddMaterial& e) {
    return e.textures[slot_index(TextureSlot::BaseColor)].has_value() ||
           !(e.material.base_color_sampler == TextureSampler{});
}
bool has_extension(const UpdateMaterial& e) {
    return e.textures[slot_index(TextureSlot::BaseColor)].has_value() || e.wrap.has_value() ||
           e.filter.has_value();
}

// Step: a material's texture slots beyond the base colour's, tagged fields under TEXTURE_SLOTS'
// numbers: an add's as the texture id, an update's as the optional id (null: none) ------------

template <class E>
constexpr bool HAS_SLOTS = Kind<E, AddMaterial> || Kind<E, UpdateMaterial>;
template <class E>
constexpr bool HAS_ATTRIBUTES =
    Kind<E, AddMesh> || Kind<E, UpdateMeshPositions> || Kind<E, ReplaceMeshTopology>;

constexpr bool slot_tags_free() {
    for (const TextureSlotInfo& s : TEXTURE_SLOTS) {
        if (s.slot == TextureSlot::BaseColor) continue;
        if (s.tag < 32 || s.tag >= 64) return false;
        bool taken = false;
        for_each_field<MaterialFields>([&](const auto& row) { taken |= row.info.tag == s.tag; });
        if (taken) return false;
    }
    return true;
}
static_assert(slot_tags_free(), "texture slot tags are in [32, 64) and no material row has them");
template <class A>
constexpr bool attribute_tag_free() {
    if (A::tag == 0) return true;
    bool taken = false;
    for_each_field<MeshFields>([&](const auto& row) { taken |= row.info.tag == A::tag; });
    return A::tag < 64 && !taken;
}
/// A curve mesh's strands (an add's when not empty, a topology change's when set): a tagged
/// field of the mesh edits that have them.
constexpr uint8_t STRANDS_TAG = 35;
static_assert(attribute_tag_free<Uvs1Attribute>() && attribute_tag_free<TangentsAttribute>() &&
                  attribute_tag_free<RadiiAttribute>() &&
                  Uvs1Attribute::tag != TangentsAttribute::tag &&
                  RadiiAttribute::tag != TangentsAttribute::tag &&
                  RadiiAttribute::tag != Uvs1Attribute::tag && RadiiAttribute::tag != STRANDS_TAG,
              "vertex attribute tags are below 64, distinct, and no mesh row has them");
template <class E>
constexpr bool HAS_STRANDS = Kind<E, AddMesh> || Kind<E, ReplaceMeshTopology>;

bool strands_present(const AddMesh& e) {
    return !e.strands.empty();
}
bool strands_present(const ReplaceMeshTopology& e) {
    return e.strands.has_value();
}
std::vector<uint32_t>& strands_array(AddMesh& e) {
    return e.strands;
}
std::vector<uint32_t>& strands_array(ReplaceMeshTopology& e) {
    return e.strands ? *e.strands : e.strands.emplace();
}
const std::vector<uint32_t>& strands_array(const AddMesh& e) {
    return e.strands;
}
const std::vector<uint32_t>& strands_array(const ReplaceMeshTopology& e) {
    return *e.strands;
}

/// Whether an edit's attribute `A` is there: an add's when not empty, an update's when set (an
/// update's empty array removes it).
template <class A>
bool attribute_present(const AddMesh& e) {
    return !A::of(e).empty();
}
template <class A, class E>
bool attribute_present(const E& e) {
    return A::of(e).has_value();
}
/// The array attribute `A`'s tag holds (an update's made present for reading into).
template <class A>
auto& attribute_array(AddMesh& e) {
    return A::of(e);
}
template <class A>
const auto& attribute_array(const AddMesh& e) {
    return A::of(e);
}
template <class A, class E>
auto& attribute_array(E& e) {
    auto& value = A::of(e);
    if constexpr (std::is_const_v<E>)
        return *value;
    else
        return value ? *value : value.emplace();
}

/// Calls `f` with each vertex attribute that is a tagged field (those added after the mesh
/// edits' extension layouts were pinned).
template <class F>
void for_each_tagged_attribute(F&& f) {
    for_each_vertex_attribute([&](auto a) {
        if constexpr (decltype(a)::tag != 0) f(a);
    });
}

/// The tagged fields an edit carries outside its kind's table: a material's texture slots, a
/// mesh edit's later vertex attributes.
template <class E>
std::size_t extra_count(const E& e) {
    std::size_t n = 0;
    if constexpr (HAS_SLOTS<E>)
        for (const TextureSlotInfo& s : TEXTURE_SLOTS)
            n += s.tag != 0 && e.textures[slot_index(s.slot)].has_value();
    if constexpr (HAS_ATTRIBUTES<E>)
        for_each_tagged_attribute(
            [&](auto a) { n += attribute_present<decltype(a)>(e) ? 1 : 0; });
    if constexpr (HAS_STRANDS<E>) n += strands_present(e) ? 1 : 0;
    return n;
}

template <class E>
void write_extras(ByteWriter& w, const E& e) {
    if constexpr (HAS_SLOTS<E>) {
        for (const TextureSlotInfo& s : TEXTURE_SLOTS) {
            const auto& texture = e.textures[slot_index(s.slot)];
            if (s.tag == 0 || !texture) continue;
            w(s.tag);
            w(*texture);
        }
    }
    if constexpr (HAS_ATTRIBUTES<E>) {
        for_each_tagged_attribute([&](auto a) {
            using A = decltype(a);
            if (!attribute_present<A>(e)) return;
            w(A::tag);
            w(attribute_array<A>(e));
        });
    }
    if constexpr (HAS_STRANDS<E>) {
        if (strands_present(e)) {
            w(STRANDS_TAG);
            w(strands_array(e));
        }
    }
}

/// Reads the field tagged `tag` into `e`; false when no extra field has that tag.
template <class E>
bool read_extra(ByteReader& r, E& e, uint8_t tag) {
    bool known = false;
    if constexpr (HAS_SLOTS<E>) {
        for (const TextureSlotInfo& s : TEXTURE_SLOTS) {
            if (s.tag == 0 || s.tag != tag) continue;
            r(e.textures[slot_index(s.slot)].emplace());
            return true;
        }
    }
    if constexpr (HAS_ATTRIBUTES<E>) {
        for_each_tagged_attribute([&](auto a) {
            using A = decltype(a);
            if (known || tag != A::tag) return;
            known = true;
            r(attribute_array<A>(e));
            // Not a form any writer produces (and it would re-encode differently).
            if (r.ok() && !attribute_present<A>(e))
                r.fail("tagged " + std::string(A::name) + " hold no values");
        });
    }
    if constexpr (HAS_STRANDS<E>) {
        if (tag == STRANDS_TAG) {
            r(strands_array(e));
            if (r.ok() && strands_array(e).empty()) r.fail("tagged strands hold no values");
            return true;
        }
    }
    return known;
}

// Step: tagged fields, for the edits that carry a kind's table --------------------------------

/// The kind whose fields an edit carries and where: the kind's add value (`update` false) or
/// its update edit. `Kind` is void for edits that carry no table.
template <class E>
struct Carries {
    using Kind = void;
    static constexpr bool update = false;
};
template <class K, bool U>
struct CarriesKind {
    using Kind = K;
    static constexpr bool update = U;
};
template <>
struct Carries<AddMesh> : CarriesKind<MeshFields, false> {};
template <>
struct Carries<AddTexture> : CarriesKind<TextureFields, false> {};
template <>
struct Carries<AddMaterial> : CarriesKind<MaterialFields, false> {};
template <>
struct Carries<UpdateMaterial> : CarriesKind<MaterialFields, true> {};
template <>
struct Carries<AddInstance> : CarriesKind<InstanceFields, false> {};
template <>
struct Carries<UpdateInstance> : CarriesKind<InstanceFields, true> {};
template <>
struct Carries<AddGroup> : CarriesKind<GroupFields, false> {};
template <>
struct Carries<UpdateGroup> : CarriesKind<GroupFields, true> {};
template <>
struct Carries<AddLight> : CarriesKind<LightFields, false> {};
template <>
struct Carries<UpdateLight> : CarriesKind<LightFields, true> {};
template <>
struct Carries<SetCamera> : CarriesKind<CameraFields, true> {};
template <>
struct Carries<SetLighting> : CarriesKind<LightingFields, true> {};
template <>
struct Carries<SetTime> : CarriesKind<TimelineFields, true> {};

/// Where the carried fields live in the edit: the edit itself, or the value an add holds.
template <class E>
auto& carried(E& e) {
    if constexpr (Kind<E, AddMaterial>)
        return e.material;
    else if constexpr (Kind<E, AddLight>)
        return e.light;
    else
        return e;
}

/// Whether a tagged field is there: an update's when set, an add's when not its default.
template <class Row, class V>
bool tagged_present(const Row& row, const V& v, bool update) {
    using K = typename Row::Kind;
    if constexpr (requires { (v.*(row.update)).has_value(); }) {
        if (update) return (v.*(row.update)).has_value();
    }
    if constexpr (std::is_same_v<V, typename K::Add>) {
        static const typename K::Add defaults{};
        return !(v.*(row.add) == defaults.*(row.add));
    }
    return false;
}

/// Calls `f` with each row of the table `E` carries (none for edits that carry no table).
template <class E, class F>
void for_each_carried_row(F&& f) {
    using C = Carries<E>;
    if constexpr (!std::is_void_v<typename C::Kind>) for_each_field<typename C::Kind>(f);
}

template <class E>
std::size_t tagged_count(const E& e) {
    std::size_t n = extra_count(e);
    for_each_carried_row<E>([&](const auto& row) {
        if (row.info.tag != 0 && tagged_present(row, carried(e), Carries<E>::update)) ++n;
    });
    return n;
}

template <class E>
void write_tagged(ByteWriter& w, const E& e) {
    w(uint8_t(tagged_count(e)));
    const auto& v = carried(e);
    for_each_carried_row<E>([&](const auto& row) {
        constexpr bool update = Carries<E>::update;
        if (row.info.tag == 0 || !tagged_present(row, v, update)) return;
        w(row.info.tag);
        if constexpr (update)
            w(*(v.*(row.update)));
        else
            w(v.*(row.add));
    });
    write_extras(w, e);
}

/// Where the field tagged `tag` comes in write_tagged's order for edits of kind `E` (table rows,
/// texture slots, vertex attributes, strands); -1 when no field of `E` has that tag.
template <class E>
int write_rank(uint8_t tag) {
    int rank = 0, found = -1;
    auto at = [&](uint8_t t) {
        if (t == tag && found < 0) found = rank;
        ++rank;
    };
    for_each_carried_row<E>([&](const auto& row) {
        if (row.info.tag != 0) at(row.info.tag);
    });
    if constexpr (HAS_SLOTS<E>)
        for (const TextureSlotInfo& s : TEXTURE_SLOTS)
            if (s.tag != 0) at(s.tag);
    if constexpr (HAS_ATTRIBUTES<E>) for_each_tagged_attribute([&](auto a) { at(a.tag); });
    if constexpr (HAS_STRANDS<E>) at(STRANDS_TAG);
    return found;
}

template <class E>
void read_tagged(ByteReader& r, E& e) {
    if constexpr (std::is_void_v<typename Carries<E>::Kind> && !HAS_SLOTS<E> && !HAS_ATTRIBUTES<E>)
        return r.fail("tagged fields on an edit that has none");
    uint8_t count = 0;
    r(count);
    if (r.ok() && count == 0) r.fail("an empty tagged section");
    int last_rank = -1;
    auto& v = carried(e);
    for (uint8_t i = 0; i < count && r.ok(); ++i) {
        uint8_t tag = 0;
        r(tag);
        if (!r.ok()) return;
        // Only the writer's order decodes: any other would re-encode differently.
        const int rank = write_rank<E>(tag);
        if (rank < 0) return r.fail("unknown field tag " + std::to_string(tag));
        if (rank <= last_rank)
            return r.fail("field tag " + std::to_string(tag) + " twice or out of order");
        last_rank = rank;
        bool known = false;
        for_each_carried_row<E>([&](const auto& row) {
            if (row.info.tag == 0 || row.info.tag != tag) return;
            known = true;
            if constexpr (Carries<E>::update) {
                (v.*(row.update)).emplace();
                r(*(v.*(row.update)));
            } else {
                r(v.*(row.add));
                // Not a form any writer produces (and it would re-encode differently).
                if (r.ok() && !tagged_present(row, v, false))
                    r.fail("tagged field " + std::to_string(tag) + " holds its default");
            }
        });
        if (!known) read_extra(r, e, tag);
    }
}

/// Edit count bit: the batch's info (its kind, time and message) follows the count.
constexpr uint32_t WITH_INFO = 0x80000000u;

template <class Io, Kind<BatchInfo> E>
void info_fields(Io& io, E& info) {
    io(info.kind, info.target, info.time_ms, info.message);
}

/// A default-constructed edit of kind `tag` (tag < variant size).
template <std::size_t... I>
Edit make_edit(std::size_t tag, std::index_sequence<I...>) {
    static constexpr Edit (*MAKE[])() = {[] { return Edit(std::in_place_index<I>); }...};
    return MAKE[tag]();
}

}  // namespace

const char* edit_kind_name(std::size_t index) {
    return index < std::size(KIND_NAMES) ? KIND_NAMES[index] : "unknown";
}

uint32_t edit_count(std::string_view bytes) {
    uint32_t count = 0;
    if (bytes.size() >= sizeof count) std::memcpy(&count, bytes.data(), sizeof count);
    return count & ~WITH_INFO;
}

void encode_batch(const EditBatch& batch, std::string& out) {
    ByteWriter w(out);
    const bool with_info = !batch.info.empty();
    w(uint32_t(batch.edits.size()) | (with_info ? WITH_INFO : 0));
    if (with_info) info_fields(w, batch.info);
    for (const Edit& edit : batch.edits) {
        std::visit(
            [&](const auto& e) {
                const bool extended = has_extension(e);
                const bool tagged = tagged_count(e) != 0;
                w(uint8_t(edit.index() | (extended ? EXTENDED : 0) | (tagged ? TAGGED : 0)));
                fields(w, e);
                if (extended) extension(w, e);
                if (tagged) write_tagged(w, e);
            },
            edit);
    }
}

Status decode_each(std::string_view bytes, const std::function<Status(Edit&&)>& sink,
                   BatchInfo* info) {
    ByteReader r(bytes);
    uint32_t count = 0;
    r(count);
    if (r.ok() && (count & WITH_INFO) != 0) {
        count &= ~WITH_INFO;
        BatchInfo read;
        info_fields(r, read);
        // Not a form any writer produces (and it would re-encode differently).
        if (r.ok() && read.empty()) r.fail("an empty batch info");
        if (r.ok() && read.message.size() > MAX_BATCH_MESSAGE_BYTES)
            r.fail("a batch message of " + std::to_string(read.message.size()) + " bytes");
        if (info) *info = std::move(read);
    }
    // Every edit takes at least its tag byte: a count beyond that is corruption.
    if (r.ok() && count > r.remaining()) r.fail("edit count " + std::to_string(count));
    for (uint32_t i = 0; i < count && r.ok(); ++i) {
        uint8_t tag = 0;
        r(tag);
        if (!r.ok()) break;
        const bool extended = (tag & EXTENDED) != 0;
        const bool tagged = (tag & TAGGED) != 0;
        tag &= uint8_t(~(EXTENDED | TAGGED));
        if (tag >= std::variant_size_v<Edit>) {
            r.fail("unknown edit kind " + std::to_string(tag));
            break;
        }
        Edit edit = make_edit(tag, std::make_index_sequence<std::variant_size_v<Edit>>());
        std::visit(
            [&](auto& e) {
                fields(r, e);
                if (extended) extension(r, e);
                // The encoder sets the bit exactly when there is something to extend with: a bit
                // on a kind without extension fields, or on extension fields that all say
                // "absent", is not a form any writer produces (and would re-encode differently).
                if (r.ok() && extended && !has_extension(e))
                    r.fail("extension bit on an edit with no extension fields");
                if (tagged) read_tagged(r, e);
            },
            edit);
        if (!r.ok()) {
            return failure(ErrorCode::InvalidArgument, "edit " + std::to_string(i) + " (" +
                                                           KIND_NAMES[tag] + "): " + r.error());
        }
        if (Status s = sink(std::move(edit)); !s) {
            Error e = std::move(s).error();
            e.edit_index = i;
            return Unexpected(std::move(e));
        }
    }
    if (r.ok() && r.remaining() != 0)
        r.fail(std::to_string(r.remaining()) + " bytes after the last edit");
    if (!r.ok()) return failure(ErrorCode::InvalidArgument, "edit batch: " + r.error());
    return {};
}

Result<EditBatch> decode_batch(std::string_view bytes) {
    EditBatch batch;
    // The count is a hint only (decode_each checks it against the bytes left).
    if (const uint32_t count = edit_count(bytes); count <= bytes.size())
        batch.edits.reserve(count);
    Status s = decode_each(
        bytes,
        [&](Edit&& e) -> Status {
            batch.edits.push_back(std::move(e));
            return {};
        },
        &batch.info);
    if (!s) return Unexpected(std::move(s).error());
    return batch;
}

}  // namespace strata::durable

#include "engine/durable/edit_codec.h"

#include <concepts>
#include <iterator>
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
                  TAG_IS<15, UpdateGroup> && TAG_IS<16, RemoveGroup> &&
                  std::variant_size_v<Edit> == 17,
              "journal kind tags are the Edit variant's indices: append new kinds at the end");

// An add_instance or update_instance that names a parent group is written under a tag of its own:
// the fields of the older layout, then the parent. Files written before groups existed keep
// reading back, and an edit without a parent is written exactly as before.
constexpr uint8_t TAG_ADD_INSTANCE_WITH_PARENT = 64;
constexpr uint8_t TAG_UPDATE_INSTANCE_WITH_PARENT = 65;

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
                                      "remove_group"};
static_assert(std::size(KIND_NAMES) == std::variant_size_v<Edit>);

/// `E` is T or const T: the same function writes (const) and reads (mutable).
template <class E, class T>
concept Kind = std::same_as<std::remove_const_t<E>, T>;

// Step: one layout per edit kind -----------------------------------------------------------------

template <class Io, Kind<AddMesh> E>
void fields(Io& io, E& e) {
    io(e.id, e.positions, e.triangles, e.build, e.material);
}
template <class Io, Kind<UpdateMeshPositions> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.offset, e.positions);
}
template <class Io, Kind<ReplaceMeshTopology> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.positions, e.triangles);
}
template <class Io, Kind<RemoveMesh> E>
void fields(Io& io, E& e) {
    io(e.mesh);
}
template <class Io, Kind<AddMaterial> E>
void fields(Io& io, E& e) {
    io(e.id, e.material);
}
template <class Io, Kind<UpdateMaterial> E>
void fields(Io& io, E& e) {
    io(e.material, e.base_color, e.roughness, e.metallic, e.emission);
}
template <class Io, Kind<AddInstance> E>
void fields(Io& io, E& e) {
    io(e.id, e.mesh, e.material, e.transform, e.visible, e.mask, e.user_id);
}
template <class Io, Kind<UpdateInstance> E>
void fields(Io& io, E& e) {
    io(e.instance, e.material, e.transform, e.visible, e.mask, e.user_id);
}
template <class Io, Kind<SetTransform> E>
void fields(Io& io, E& e) {
    io(e.instance, e.transform);
}
template <class Io, Kind<RemoveInstance> E>
void fields(Io& io, E& e) {
    io(e.instance);
}
template <class Io, Kind<MarkDirty> E>
void fields(Io& io, E& e) {
    io(e.mesh, e.action);
}
template <class Io, Kind<SetCamera> E>
void fields(Io& io, E& e) {
    io(e.eye, e.target, e.up, e.fov_y_deg);
}
template <class Io, Kind<SetLighting> E>
void fields(Io& io, E& e) {
    io(e.sun_direction, e.sun_color, e.sky_color, e.sky_intensity);
}
template <class Io, Kind<Clear> E>
void fields(Io&, E&) {}
template <class Io, Kind<AddGroup> E>
void fields(Io& io, E& e) {
    io(e.id, e.parent, e.transform, e.visible);
}
template <class Io, Kind<UpdateGroup> E>
void fields(Io& io, E& e) {
    io(e.group, e.parent, e.transform, e.visible);
}
template <class Io, Kind<RemoveGroup> E>
void fields(Io& io, E& e) {
    io(e.group, e.recursive);
}

/// A default-constructed edit of kind `tag` (tag < variant size).
template <std::size_t... I>
Edit make_edit(std::size_t tag, std::index_sequence<I...>) {
    static constexpr Edit (*MAKE[])() = {[] { return Edit(std::in_place_index<I>); }...};
    return MAKE[tag]();
}

}  // namespace

void encode_batch(const EditBatch& batch, std::string& out) {
    ByteWriter w(out);
    w(uint32_t(batch.edits.size()));
    for (const Edit& edit : batch.edits) {
        if (const auto* add = std::get_if<AddInstance>(&edit); add && add->parent) {
            w(TAG_ADD_INSTANCE_WITH_PARENT);
            fields(w, *add);
            w(*add->parent);
            continue;
        }
        if (const auto* upd = std::get_if<UpdateInstance>(&edit); upd && upd->parent) {
            w(TAG_UPDATE_INSTANCE_WITH_PARENT);
            fields(w, *upd);
            w(*upd->parent);
            continue;
        }
        w(uint8_t(edit.index()));
        std::visit([&](const auto& e) { fields(w, e); }, edit);
    }
}

Result<EditBatch> decode_batch(std::string_view bytes) {
    ByteReader r(bytes);
    uint32_t count = 0;
    r(count);
    EditBatch batch;
    // Every edit takes at least its tag byte: a count beyond that is corruption, not a reason to
    // reserve gigabytes.
    if (r.ok() && count > r.remaining()) r.fail("edit count " + std::to_string(count));
    if (r.ok()) batch.edits.reserve(count);
    for (uint32_t i = 0; i < count && r.ok(); ++i) {
        uint8_t tag = 0;
        r(tag);
        if (!r.ok()) break;
        if (tag == TAG_ADD_INSTANCE_WITH_PARENT) {
            AddInstance e;
            fields(r, e);
            std::string parent;
            r(parent);
            e.parent = std::move(parent);
            if (!r.ok()) {
                r.fail("");
                return failure(ErrorCode::InvalidArgument,
                               "edit " + std::to_string(i) + " (add_instance): " + r.error());
            }
            batch.edits.push_back(std::move(e));
            continue;
        }
        if (tag == TAG_UPDATE_INSTANCE_WITH_PARENT) {
            UpdateInstance e;
            fields(r, e);
            std::optional<std::string> parent;
            r(parent);
            e.parent = std::move(parent);
            if (!r.ok()) {
                r.fail("");
                return failure(ErrorCode::InvalidArgument,
                               "edit " + std::to_string(i) + " (update_instance): " + r.error());
            }
            batch.edits.push_back(std::move(e));
            continue;
        }
        if (tag >= std::variant_size_v<Edit>) {
            r.fail("unknown edit kind " + std::to_string(tag));
            break;
        }
        Edit edit = make_edit(tag, std::make_index_sequence<std::variant_size_v<Edit>>());
        std::visit([&](auto& e) { fields(r, e); }, edit);
        if (!r.ok()) {
            r.fail("");  // keeps the first message
            return failure(ErrorCode::InvalidArgument, "edit " + std::to_string(i) + " (" +
                                                           KIND_NAMES[tag] + "): " + r.error());
        }
        batch.edits.push_back(std::move(edit));
    }
    if (r.ok() && r.remaining() != 0)
        r.fail(std::to_string(r.remaining()) + " bytes after the last edit");
    if (!r.ok()) return failure(ErrorCode::InvalidArgument, "edit batch: " + r.error());
    return batch;
}

}  // namespace strata::durable

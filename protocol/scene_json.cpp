#include "protocol/scene_json.h"

#include <charconv>

#include "engine/image/texture_decode.h"
#include "protocol/field_json.h"
#include "protocol/framing.h"

namespace strata::protocol {

namespace {

/// The double with the shortest decimal form that reads back as `f`, so that 0.45f prints as
/// 0.45 and not 0.44999998807907104.
double shortest(float f) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, f);
    double d = f;
    std::from_chars(buf, r.ptr, d);
    return d;
}

Json floats_to_json(const float* v, std::size_t n) {
    Json out = Json::array();
    for (std::size_t i = 0; i < n; ++i) out.push_back(shortest(v[i]));
    return out;
}

Json material_fields(const Material& m) {
    Json j = {{"sampler",
               {{"wrap", texture_wrap_name(m.base_color_sampler.wrap)},
                {"filter", texture_filter_name(m.base_color_sampler.filter)}}}};
    write_fields<MaterialFields>(j, m);
    return j;
}

/// The id of a material handle, or null for the default.
Json material_ref(const Scene& s, MaterialHandle h) {
    const auto m = s.material(h);
    return m ? Json(m.value()->id) : Json(nullptr);
}

/// The id of a group handle, or null for the root.
Json group_ref(const Scene& s, GroupHandle h) {
    const auto g = s.group(h);
    return g ? Json(g.value()->id) : Json(nullptr);
}

}  // namespace

Json affine_to_json(const Affine& a) {
    return floats_to_json(a.to_rows16().data(), 16);
}

Json float_to_json(float f) {
    return shortest(f);
}

Json vec3_to_json(const Vec3& v) {
    return floats_to_json(&v.x, 3);
}

Json camera_to_json(const Camera& c) {
    Json j = Json::object();
    write_fields<CameraFields>(j, c);
    return j;
}

Json lighting_to_json(const Lighting& l) {
    Json j = Json::object();
    write_fields<LightingFields>(j, l);
    return j;
}

Json timeline_to_json(const Timeline& t) {
    Json j = Json::object();
    write_fields<TimelineFields>(j, t);
    return j;
}

Json bounds_to_json(const Bounds3& b) {
    if (b.empty()) return nullptr;
    return {{"min", vec3_to_json(b.lower)}, {"max", vec3_to_json(b.upper)}};
}

Json scene_summary_to_json(const Scene& s) {
    const SceneCounts c = s.counts();
    return {{"version", s.version()},
            {"counts",
             {{"meshes", c.meshes},
              {"instances", c.instances},
              {"materials", c.materials},
              {"groups", c.groups},
              {"lights", c.lights},
              {"textures", c.textures},
              {"triangles", c.triangles},
              {"instanced_triangles", c.instanced_triangles}}},
            {"bounds", bounds_to_json(s.world_bounds())},
            {"camera", camera_to_json(s.camera())},
            {"lighting", lighting_to_json(s.lighting())},
            {"timeline", timeline_to_json(s.timeline())}};
}

Bounds3 mesh_bounds(const MeshRecord& m) {
    return m.bounds();
}

Json mesh_json(const Scene& s, MeshHandle h, const MeshRecord& m) {
    Json j{{"id", m.id},
           {"index", h.index},
           {"version", s.version()},
           {"vertices", m.positions.size()},
           {"triangles", m.triangles.size()},
           {"primitives", m.primitive_count()},
           {"strands", m.strands.size()},
           {"motion_keys", m.motion_keys()},
           {"instances", m.users.size()},
           {"material", material_ref(s, m.material)},
           {"build",
            {{"prefer", build_preference_name(m.build.prefer)},
             {"allow_refit", m.build.allow_refit},
             {"compact", m.build.compact}}},
           {"bounds", bounds_to_json(mesh_bounds(m))}};
    // Whether it has each vertex attribute.
    for_each_vertex_attribute(
        [&](auto a) { j[std::string(a.name)] = !decltype(a)::of(m).empty(); });
    write_fields<MeshFields>(j, m);
    return j;
}

Json instance_json(const Scene& s, InstanceHandle h, const InstanceRecord& i,
                   const Bounds3& mesh_local_bounds) {
    Json j{{"id", i.id},
           {"index", h.index},
           {"version", s.version()},
           {"mesh", s.mesh(i.mesh).value()->id},
           {"material", material_ref(s, i.material)},
           {"resolved_material", material_fields(s.resolved_material(i))},
           {"parent", group_ref(s, i.parent)},
           {"world_transform", affine_to_json(i.world)},
           {"world_visible", i.world_visible},
           {"bounds", bounds_to_json(i.world.transform_bounds(mesh_local_bounds))}};
    write_fields<InstanceFields>(j, i);
    return j;
}

Json group_json(const Scene& s, GroupHandle h, const GroupRecord& g) {
    Json j{{"id", g.id},
           {"index", h.index},
           {"version", s.version()},
           {"parent", group_ref(s, g.parent)},
           {"world_transform", affine_to_json(g.world)},
           {"world_visible", g.world_visible},
           {"children",
            {{"groups", g.children.groups.size()}, {"instances", g.children.instances.size()}}}};
    write_fields<GroupFields>(j, g);
    return j;
}

Json material_json(const Scene& s, const MaterialRecord& m) {
    Json j = material_fields(m.material);
    j["id"] = m.id;
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        const auto t = s.texture(m.textures[slot_index(slot.slot)]);
        j[std::string(slot.field)] = t ? Json(t.value()->id) : Json(nullptr);
    }
    j["version"] = s.version();
    return j;
}

Json light_json(const Scene& s, const LightRecord& r) {
    Json j{{"id", r.id}, {"version", s.version()}};
    write_fields<LightFields>(j, r.light);
    return j;
}

std::optional<Json> mesh_to_json(const Scene& s, std::string_view id) {
    const MeshHandle h = s.find_mesh(id);
    const auto r = s.mesh(h);
    if (!r) return std::nullopt;
    return mesh_json(s, h, *r.value());
}

std::optional<Json> instance_to_json(const Scene& s, std::string_view id) {
    const InstanceHandle h = s.find_instance(id);
    const auto r = s.instance(h);
    if (!r) return std::nullopt;
    return instance_json(s, h, *r.value(), mesh_bounds(*s.mesh(r.value()->mesh).value()));
}

std::optional<Json> group_to_json(const Scene& s, std::string_view id) {
    const GroupHandle h = s.find_group(id);
    const auto r = s.group(h);
    if (!r) return std::nullopt;
    // One group's document has the world bounds of its subtree (a walk over it); listings,
    // which would walk every subtree once per group, leave them out.
    Json j = group_json(s, h, *r.value());
    j["bounds"] = bounds_to_json(subtree_bounds(s, h));
    return j;
}

std::optional<Json> light_to_json(const Scene& s, std::string_view id) {
    const LightRecord* r = s.lights().get(s.find_light(id));
    if (!r) return std::nullopt;
    return light_json(s, *r);
}

Json texture_json(const Scene& s, const TextureRecord& t) {
    const char* format = texture_format(*t.encoded);
    Json j{{"id", t.id},
           {"width", t.image->width},
           {"height", t.image->height},
           {"format", format ? format : "unknown"},
           {"encoded_bytes", t.encoded->size()},
           {"decoded_bytes", t.image->bytes()},
           {"version", s.version()}};
    write_fields<TextureFields>(j, t);
    return j;
}

std::optional<Json> texture_to_json(const Scene& s, std::string_view id) {
    const auto r = s.texture(s.find_texture(id));
    if (!r) return std::nullopt;
    return texture_json(s, *r.value());
}

std::optional<Json> material_to_json(const Scene& s, std::string_view id) {
    const auto r = s.material(s.find_material(id));
    if (!r) return std::nullopt;
    return material_json(s, *r.value());
}

}  // namespace strata::protocol

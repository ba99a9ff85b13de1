#pragma once
// The field table of every object kind (field_table.h says what a row holds and who reads it).
//
// Adding a field: its member in the kind's record, add edit and update edit (types.h, edits.h,
// scene.h) and a row here with the next free `tag` of its kind. Rows with tag 0 are the kinds'
// first journal layout: their order is that layout and never changes.

#include <string_view>

#include "engine/core/math.h"
#include "engine/scene/field_table.h"
#include "engine/scene/scene.h"

namespace strata {

inline constexpr std::string_view NAME_DOC =
    "A display name: free text for listings, picks and the viewer (not unique, not an id).";

inline constexpr std::string_view ASSET_DOC =
    "The file the group was imported from (POST /v1/assets sets it). A group with one is an "
    "asset: it owns every object whose id begins with the group's id and a '.', unless a "
    "longer asset id owns it; /v1/assets/{id} lists, deletes and re-imports them as one.";

/// What a change to a field marked `dirty` costs the next commit, as the docs say it (the
/// least-work tests hold the engine to it).
constexpr std::string_view commit_cost(InstanceDirty dirty) {
    return (INSTANCE_TLAS_BITS & dirty).any() ? "TLAS update" : "no BVH work";
}
constexpr std::string_view commit_cost(GroupDirty dirty) {
    return dirty == GroupDirty{} ? "no BVH work" : "TLAS update of the instances below";
}
constexpr std::string_view commit_cost(ClockDirty) {
    return "TLAS update of the animated instances that move";
}
template <class D>
constexpr std::string_view commit_cost(D) {
    return "no BVH work";
}

inline constexpr Limits COORDINATE = closed(-MAX_COORDINATE, MAX_COORDINATE);
inline constexpr Limits LOD_DISTANCE = closed(0.0, MAX_COORDINATE);

inline constexpr std::string_view LOD_NEAR_DOC =
    "Under a level-of-detail group (lod: true): the LOD distance from which this child and all "
    "below it are drawn: the distance from the camera (for every ray of a frame, shadow and "
    "bounce rays too) to the group's origin. Elsewhere it has no effect.";
inline constexpr std::string_view LOD_FAR_DOC =
    "Under a level-of-detail group: the LOD distance from which this child is no longer drawn; "
    "above lod_near. The default, 1e15, is no limit.";
inline constexpr std::string_view INTERPOLATION_DOC =
    "How motion keys and keyframes are interpolated: linear blends the matrices (a turning "
    "object shrinks between keys); srt interpolates scale, skew and translation linearly and the "
    "rotation by slerp, the shorter way between two keys (turn less than 180 degrees per key).";
inline constexpr std::string_view ANIMATION_LOOP_DOC =
    "true: the animation repeats, scene time wrapping into [first key, last key).";
/// Motion interpolations on the wire (MotionInterpolation's order).
inline constexpr std::string_view INTERPOLATIONS[] = {"linear", "srt"};
inline constexpr Limits UNIT = closed(0.0, 1.0);
inline constexpr Limits NON_NEGATIVE = at_least(0.0);

struct LightFields {
    using Record = Light;
    using Add = Light;
    using Update = UpdateLight;
    using Dirty = SceneDirty;
    static constexpr std::string_view KIND = "light";
    static constexpr std::string_view TYPES[] = {"point", "spot", "rect"};
    static constexpr auto table();
};

constexpr auto LightFields::table() {
    using K = LightFields;
    constexpr SceneDirty L = SceneDirty::Lights;
    return std::tuple{
        field<K>({"type", "point, spot or rect.", {}, TYPES}, &Light::kind, &Light::kind,
                 &UpdateLight::kind, L),
        field<K>(
            {"position", "Where a point or spot light is, or a rect light's centre.", COORDINATE},
            STRATA_FIELD_OF(K, position), L),
        field<K>({"direction", "A spot light's axis, a rect light's normal (any length but zero)."},
                 STRATA_FIELD_OF(K, direction), L),
        field<K>({"color", "Linear RGB, multiplied by the intensity.", NON_NEGATIVE},
                 STRATA_FIELD_OF(K, color), L),
        field<K>({"intensity",
                  "Point and spot: irradiance intensity * color / d^2 at distance d; rect: "
                  "radiance intensity * color from its front side.",
                  closed(0.0, 1e12)},
                 STRATA_FIELD_OF(K, intensity), L),
        field<K>({"angle_deg", "A spot light's half-angle.", above_up_to(0.0, 90.0)},
                 STRATA_FIELD_OF(K, angle_deg), L),
        field<K>({"inner_angle_deg",
                  "A spot light's full-intensity half-angle (at most angle_deg): the light fades "
                  "to 0 between it and angle_deg.",
                  closed(0.0, 90.0)},
                 STRATA_FIELD_OF(K, inner_angle_deg), L),
        field<K>({"width", "A rect light's width.", above_up_to(0.0, 1e6)},
                 STRATA_FIELD_OF(K, width), L),
        field<K>({"height", "A rect light's height.", above_up_to(0.0, 1e6)},
                 STRATA_FIELD_OF(K, height), L),
        field<K>({"name", NAME_DOC, {}, {}, 1, true}, STRATA_FIELD_OF(K, name), SceneDirty{}),
    };
}

inline constexpr std::string_view ALPHA_MODES[] = {"opaque", "mask", "blend"};
inline constexpr std::string_view COLOR_SPACES[] = {"srgb", "linear"};

/// A texture slot's coordinate set (glTF's texCoord): the mesh's uvs or its uvs1.
inline constexpr Limits UV_SETS = closed(0, 1);
inline constexpr std::string_view UV_SET_DOC =
    "The texture coordinates the slot's texture reads: 0, the mesh's uvs; 1, its uvs1 (a mesh "
    "without uvs1 reads its uvs).";

struct MaterialFields {
    using Record = Material;
    using Add = Material;
    using Update = UpdateMaterial;
    using Dirty = MaterialDirty;
    static constexpr std::string_view KIND = "material";
    static constexpr auto table();
};

constexpr auto MaterialFields::table() {
    using K = MaterialFields;
    constexpr MaterialDirty P = MaterialDirty::Params;
    return std::tuple{
        field<K>({"base_color", "Linear RGB albedo; a base_color_texture multiplies it.", UNIT},
                 STRATA_FIELD_OF(K, base_color), P),
        field<K>({"roughness", "0: a mirror, 1: fully rough.", UNIT}, STRATA_FIELD_OF(K, roughness),
                 P),
        field<K>({"metallic", "0: dielectric, 1: metal.", UNIT}, STRATA_FIELD_OF(K, metallic), P),
        field<K>({"emission", "Emitted radiance, linear RGB.", NON_NEGATIVE},
                 STRATA_FIELD_OF(K, emission), P),
        field<K>({"name", NAME_DOC, {}, {}, 1, true}, STRATA_FIELD_OF(K, name), MaterialDirty{}),
        field<K>({"alpha", "Coverage: 1 opaque, 0 invisible; the base_color_texture's alpha "
                           "multiplies it. Read only by the mask and blend alpha modes.",
                  UNIT, {}, 2},
                 STRATA_FIELD_OF(K, alpha), P),
        field<K>({"alpha_mode",
                  "opaque ignores alpha; mask cuts the surface away where alpha < alpha_cutoff; "
                  "blend lets a ray through with probability 1 - alpha (converges to alpha "
                  "blending over samples).",
                  {}, ALPHA_MODES, 3},
                 STRATA_FIELD_OF(K, alpha_mode), P),
        field<K>({"alpha_cutoff", "The mask alpha mode's threshold.", UNIT, {}, 4},
                 STRATA_FIELD_OF(K, alpha_cutoff), P),
        field<K>({"normal_scale", "Scales the normal map's X and Y (0: no effect).",
                  closed(-100.0, 100.0), {}, 5},
                 STRATA_FIELD_OF(K, normal_scale), P),
        field<K>({"occlusion_strength", "0: the occlusion texture has no effect, 1: full effect.",
                  UNIT, {}, 6},
                 STRATA_FIELD_OF(K, occlusion_strength), P),
        field<K>({"unlit",
                  "Shows the base colour (times its texture) as it is, lit by nothing and "
                  "reflecting nothing (KHR_materials_unlit).",
                  {}, {}, 7},
                 STRATA_FIELD_OF(K, unlit), P),
        field<K>({"base_color_uv_set", UV_SET_DOC, UV_SETS, {}, 8},
                 STRATA_FIELD_OF(K, base_color_uv_set), P),
        field<K>({"metallic_roughness_uv_set", UV_SET_DOC, UV_SETS, {}, 9},
                 STRATA_FIELD_OF(K, metallic_roughness_uv_set), P),
        field<K>({"normal_uv_set", UV_SET_DOC, UV_SETS, {}, 10},
                 STRATA_FIELD_OF(K, normal_uv_set), P),
        field<K>({"occlusion_uv_set", UV_SET_DOC, UV_SETS, {}, 11},
                 STRATA_FIELD_OF(K, occlusion_uv_set), P),
        field<K>({"emissive_uv_set", UV_SET_DOC, UV_SETS, {}, 12},
                 STRATA_FIELD_OF(K, emissive_uv_set), P),
    };
}

struct InstanceFields {
    using Record = InstanceRecord;
    using Add = AddInstance;
    using Update = UpdateInstance;
    using Dirty = InstanceDirty;
    static constexpr std::string_view KIND = "instance";
    static constexpr auto table();
};

constexpr auto InstanceFields::table() {
    using K = InstanceFields;
    return std::tuple{
        field<K>({"transform", "Object to parent space (to world space at the root)."},
                 STRATA_FIELD_OF(K, transform), InstanceDirty::Transform),
        field<K>({"visible", "Its own flag; hidden too while a group above it is hidden."},
                 STRATA_FIELD_OF(K, visible), InstanceDirty::Visibility),
        field<K>({"mask", "Embree's 32-bit geometry mask, set on the instance in the TLAS."},
                 STRATA_FIELD_OF(K, mask), InstanceDirty::Mask),
        field<K>({"user_id",
                  "The client's 32-bit value, reported by picks and its AOV.",
                  {},
                  {},
                  0,
                  true},
                 STRATA_FIELD_OF(K, user_id), InstanceDirty::UserId),
        field<K>({"name", NAME_DOC, {}, {}, 1, true},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, name), InstanceDirty{}),
        field<K>({"motion",
                  "Motion keys for motion blur: 2 to 129 transforms in the instance's own space, "
                  "evenly spaced over the frame (time 0 to 1) and interpolated linearly; the "
                  "instance at time t is its world transform times the keys at t. [] or absent: "
                  "no motion.",
                  {}, {}, 2},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, motion), InstanceDirty::Transform),
        field<K>({"lod_near", LOD_NEAR_DOC, LOD_DISTANCE, {}, 3},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, lod_near), InstanceDirty::Lod),
        field<K>({"lod_far", LOD_FAR_DOC, LOD_DISTANCE, {}, 4},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, lod_far), InstanceDirty::Lod),
        field<K>({"motion_interpolation", INTERPOLATION_DOC, {}, INTERPOLATIONS, 5},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, motion_interpolation),
                 InstanceDirty::Transform),
        field<K>({"animation",
                  "Keyframes: the instance's transform (relative to its parent, as transform) at "
                  "scene times in seconds, increasing; non-empty, they and the scene's time "
                  "(set_time) place it instead of transform, interpolated as "
                  "motion_interpolation says, holding the first and last key outside them. "
                  "Over a frame it moves as they say, so an open shutter blurs it. Not with "
                  "motion. [] or absent: none.",
                  {}, {}, 6},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, animation), InstanceDirty::Transform),
        field<K>({"animation_loop", ANIMATION_LOOP_DOC, {}, {}, 7},
                 STRATA_BOXED_FIELD_OF(K, InstanceRare, rare, animation_loop),
                 InstanceDirty::Transform),
    };
}

struct GroupFields {
    using Record = GroupRecord;
    using Add = AddGroup;
    using Update = UpdateGroup;
    using Dirty = GroupDirty;
    static constexpr std::string_view KIND = "group";
    static constexpr auto table();
};

constexpr auto GroupFields::table() {
    using K = GroupFields;
    return std::tuple{
        field<K>({"transform", "Applies to everything below the group."},
                 STRATA_FIELD_OF(K, transform), GroupDirty::Transform),
        field<K>({"visible", "false hides everything below the group."},
                 STRATA_FIELD_OF(K, visible), GroupDirty::Visibility),
        field<K>({"name", NAME_DOC, {}, {}, 1, true}, STRATA_FIELD_OF(K, name), GroupDirty{}),
        field<K>({"asset", ASSET_DOC, {}, {}, 2}, STRATA_FIELD_OF(K, asset), GroupDirty{}),
        field<K>({"lod",
                  "true: a level-of-detail group, whose children are levels; each child is "
                  "drawn for the rays whose LOD distance from the group's origin lies in its "
                  "[lod_near, lod_far).",
                  {}, {}, 3},
                 STRATA_FIELD_OF(K, lod), GroupDirty::Lod),
        field<K>({"lod_near", LOD_NEAR_DOC, LOD_DISTANCE, {}, 4}, STRATA_FIELD_OF(K, lod_near),
                 GroupDirty::Lod),
        field<K>({"lod_far", LOD_FAR_DOC, LOD_DISTANCE, {}, 5}, STRATA_FIELD_OF(K, lod_far),
                 GroupDirty::Lod),
        field<K>({"motion",
                  "Motion keys, as an instance's: 2 to 129 transforms in the group's own space "
                  "over the frame; everything below moves with them (its own keys composed). "
                  "[] or absent: no motion.",
                  {}, {}, 6},
                 STRATA_FIELD_OF(K, motion), GroupDirty::Transform),
        field<K>({"motion_interpolation", INTERPOLATION_DOC, {}, INTERPOLATIONS, 7},
                 STRATA_FIELD_OF(K, motion_interpolation), GroupDirty::Transform),
        field<K>({"animation",
                  "Keyframes, as an instance's: the group's transform at scene times, carrying "
                  "everything below. Not with motion.",
                  {}, {}, 8},
                 STRATA_FIELD_OF(K, animation), GroupDirty::Transform),
        field<K>({"animation_loop", ANIMATION_LOOP_DOC, {}, {}, 9},
                 STRATA_FIELD_OF(K, animation_loop), GroupDirty::Transform),
    };
}

struct MeshFields {
    using Record = MeshRecord;
    using Add = AddMesh;
    using Update = NoUpdate;
    using Dirty = MeshDirty;
    static constexpr std::string_view KIND = "mesh";
    static constexpr std::string_view KINDS[] = {"triangles", "points", "curves"};
    static constexpr std::string_view BASES[] = {"linear", "bezier", "bspline", "catmull_rom"};
    static constexpr std::string_view STYLES[] = {"round", "flat"};
    static constexpr auto table();
};

constexpr auto MeshFields::table() {
    using K = MeshFields;
    return std::tuple{
        field<K>({"name", NAME_DOC, {}, {}, 1, true}, &MeshRecord::name, &AddMesh::name, nullptr,
                 MeshDirty{}),
        field<K>({"kind",
                  "triangles (indices), points (a sphere per vertex, radius from radii) or "
                  "curves (strands of control vertices with radii). Fixed when added.",
                  {}, KINDS, 2},
                 &MeshRecord::kind, &AddMesh::kind, nullptr, MeshDirty{}),
        field<K>({"basis",
                  "Curves: how control vertices make segments. linear (n >= 2 per strand), "
                  "bezier (cubic, 3k + 1), bspline or catmull_rom (n >= 4).",
                  {}, BASES, 3},
                 &MeshRecord::basis, &AddMesh::basis, nullptr, MeshDirty{}),
        field<K>({"style", "Curves: round (a tube) or flat (a ribbon facing the ray).", {},
                  STYLES, 4},
                 &MeshRecord::style, &AddMesh::style, nullptr, MeshDirty{}),
    };
}

struct TextureFields {
    using Record = TextureRecord;
    using Add = AddTexture;
    using Update = NoUpdate;
    using Dirty = SceneDirty;
    static constexpr std::string_view KIND = "texture";
    static constexpr auto table();
};

constexpr auto TextureFields::table() {
    using K = TextureFields;
    return std::tuple{
        field<K>({"name", NAME_DOC, {}, {}, 1, true}, &TextureRecord::name, &AddTexture::name,
                 nullptr, SceneDirty{}),
        field<K>({"color_space",
                  "srgb: colours (base colour, emissive), decoded to linear; linear: data "
                  "(normal, metallic-roughness and occlusion maps), read as stored.",
                  {}, COLOR_SPACES, 2},
                 &TextureRecord::color_space, &AddTexture::color_space, nullptr, SceneDirty{}),
    };
}

struct CameraFields {
    using Record = Camera;
    using Add = Camera;
    using Update = SetCamera;
    using Dirty = SceneDirty;
    static constexpr std::string_view KIND = "camera";
    static constexpr auto table();
};

constexpr auto CameraFields::table() {
    using K = CameraFields;
    constexpr SceneDirty C = SceneDirty::Camera;
    return std::tuple{
        field<K>({"eye", "Where the camera is.", COORDINATE}, STRATA_FIELD_OF(K, eye), C),
        field<K>({"target", "The point it looks at (not the eye).", COORDINATE},
                 STRATA_FIELD_OF(K, target), C),
        field<K>({"up", "Up on the image (not along the view)."}, STRATA_FIELD_OF(K, up), C),
        field<K>({"fov_y_deg", "Vertical field of view.", open(0.0, 180.0)},
                 STRATA_FIELD_OF(K, fov_y_deg), C),
        field<K>({"shutter_open",
                  "When the shutter opens, in frame time (0 to 1, the span motion keys cover). "
                  "Each sample of a render picks a time between it and shutter_close.",
                  UNIT, {}, 1},
                 STRATA_FIELD_OF(K, shutter_open), C),
        field<K>({"shutter_close",
                  "When the shutter closes (at least shutter_open); equal to it: no motion blur.",
                  UNIT, {}, 2},
                 STRATA_FIELD_OF(K, shutter_close), C),
    };
}

struct TimelineFields {
    using Record = Timeline;
    using Add = Timeline;
    using Update = SetTime;
    using Dirty = ClockDirty;
    static constexpr std::string_view KIND = "timeline";
    static constexpr auto table();
};

constexpr auto TimelineFields::table() {
    using K = TimelineFields;
    return std::tuple{
        field<K>({"time",
                  "The scene's time in seconds: where animations (an instance's animation "
                  "keyframes) are evaluated. Changing it updates the animated instances only.",
                  closed(-MAX_SCENE_TIME, MAX_SCENE_TIME)},
                 STRATA_FIELD_OF(K, time), ClockDirty::Time),
        field<K>({"frame_duration",
                  "Seconds of scene time one frame spans (frame time 0 to 1, which the camera's "
                  "shutter_open and shutter_close are part of): an animated instance moving "
                  "during it blurs under an open shutter. 0: animations do not blur.",
                  closed(0.0, 3600.0)},
                 STRATA_FIELD_OF(K, frame_duration), ClockDirty::Time),
    };
}

struct LightingFields {
    using Record = Lighting;
    using Add = Lighting;
    using Update = SetLighting;
    using Dirty = SceneDirty;
    static constexpr std::string_view KIND = "lighting";
    static constexpr auto table();
};

constexpr auto LightingFields::table() {
    using K = LightingFields;
    constexpr SceneDirty L = SceneDirty::Lighting;
    return std::tuple{
        field<K>({"sun_direction", "From the scene toward the sun (any length but zero)."},
                 STRATA_FIELD_OF(K, sun_direction), L),
        field<K>({"sun_color", "The sun's irradiance, linear RGB.", NON_NEGATIVE},
                 STRATA_FIELD_OF(K, sun_color), L),
        field<K>({"sky_color", "The uniform sky's radiance, linear RGB.", NON_NEGATIVE},
                 STRATA_FIELD_OF(K, sky_color), L),
        field<K>({"sky_intensity", "Multiplies sky_color.", NON_NEGATIVE},
                 STRATA_FIELD_OF(K, sky_intensity), L),
    };
}

}  // namespace strata

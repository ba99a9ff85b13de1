#pragma once
// Plain scene value types: meshes, materials, camera and lighting.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/math.h"
#include "engine/core/result.h"
#include "engine/scene/lod.h"
#include "engine/scene/mesh_kind.h"

namespace strata {

using Triangle = glm::uvec3;

/// What a mesh's BLAS optimises for, in the spirit of OptiX's PREFER_FAST_TRACE/_BUILD flags.
enum class BuildPreference : uint8_t { FastTrace, FastBuild };

/// Per-mesh build options (OptiX build flags mapped onto Embree build qualities, see blas_store).
struct BuildOptions {
    BuildPreference prefer = BuildPreference::FastTrace;
    bool allow_refit = true;  ///< like OPTIX_BUILD_FLAG_ALLOW_UPDATE
    /// Like OPTIX_BUILD_FLAG_ALLOW_COMPACTION followed by a compacting copy: every build of the
    /// BLAS is measured at full size, then rebuilt in Embree's compact layout (blas_store.h).
    bool compact = false;

    friend bool operator==(const BuildOptions&, const BuildOptions&) = default;
};

const char* build_preference_name(BuildPreference p);

/// How texture coordinates outside [0, 1) map into an image.
enum class TextureWrap : uint8_t { Repeat, Clamp, Mirror };
/// How a texture lookup between texels is filtered.
enum class TextureFilter : uint8_t { Bilinear, Nearest };

/// How a material reads its texture (glTF's sampler, reduced to what the renderer does).
struct TextureSampler {
    TextureWrap wrap = TextureWrap::Repeat;
    TextureFilter filter = TextureFilter::Bilinear;

    friend bool operator==(const TextureSampler&, const TextureSampler&) = default;
};

const char* texture_wrap_name(TextureWrap w);
const char* texture_filter_name(TextureFilter f);

/// How a texture's texels are meant: colours (sRGB-encoded, decoded to linear once) or data
/// (normals, roughness, occlusion: the codes read as they are, 0..255 meaning 0..1).
enum class TextureColorSpace : uint8_t { Srgb, Linear };

/// How a material's coverage (`alpha` times its base-colour texture's alpha) hides its surface,
/// as glTF's alphaMode: opaque ignores it; mask cuts the surface away where coverage is below
/// `alpha_cutoff`; blend lets each ray through with probability 1 - coverage (FrameState::
/// hit_test applies them during traversal).
enum class AlphaMode : uint8_t { Opaque, Mask, Blend };

const char* alpha_mode_name(AlphaMode m);

/// The textures a material may read, as glTF 2.0's metallic-roughness material has them. Each is
/// named by the material's record (MaterialRecord::textures) and read through the material's one
/// sampler at the texture coordinate set the slot's uv_set names.
enum class TextureSlot : uint8_t { BaseColor, MetallicRoughness, Normal, Occlusion, Emissive };
inline constexpr std::size_t TEXTURE_SLOT_COUNT = 5;
template <class T>
using PerTextureSlot = std::array<T, TEXTURE_SLOT_COUNT>;

constexpr std::size_t slot_index(TextureSlot s) {
    return static_cast<std::size_t>(s);
}

/// Surface description: glTF 2.0's metallic-roughness material. Colors are linear RGB. Its
/// textures are named by the material's record (MaterialRecord::textures).
struct Material {
    Vec3 base_color{0.8f};
    float roughness = 0.5f;
    float metallic = 0.0f;
    Vec3 emission{0.0f};
    TextureSampler base_color_sampler = {};  ///< how every texture of the material is read
    std::string name = {};  ///< display name (object_fields.h)
    float alpha = 1.0f;     ///< coverage, multiplied by the base-colour texture's alpha
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float alpha_cutoff = 0.5f;        ///< mask: coverage below it is cut away
    float normal_scale = 1.0f;        ///< scales the normal map's X and Y
    float occlusion_strength = 1.0f;  ///< 0: the occlusion texture has no effect
    bool unlit = false;  ///< shows base colour as it is, without lighting (KHR_materials_unlit)
    /// The texture coordinate set each slot's texture reads: 0 (the mesh's uvs) or 1 (uvs1).
    uint32_t base_color_uv_set = 0;
    uint32_t metallic_roughness_uv_set = 0;
    uint32_t normal_uv_set = 0;
    uint32_t occlusion_uv_set = 0;
    uint32_t emissive_uv_set = 0;

    friend bool operator==(const Material&, const Material&) = default;
};

/// What one texture slot is: declared once here, read by the rules, the journal, the wire parser,
/// the JSON writer, the schema and the importers.
struct TextureSlotInfo {
    TextureSlot slot;
    std::string_view field;  ///< the material's member on the wire
    std::string_view doc;    ///< one line for the schema and the docs
    TextureColorSpace space;  ///< how a texture made for this slot is decoded (importers)
    /// The number of its entry in a material edit's tagged section (edit_codec.cpp); 0: the
    /// base-colour texture, which is part of the material's first extension layout.
    uint8_t tag;
    /// The material's member that says which texture coordinate set the slot reads.
    uint32_t Material::*uv_set;
};

inline constexpr TextureSlotInfo TEXTURE_SLOTS[TEXTURE_SLOT_COUNT] = {
    {TextureSlot::BaseColor, "base_color_texture",
     "Multiplies base_color (RGB) and alpha (A); an sRGB colour texture.", TextureColorSpace::Srgb,
     0, &Material::base_color_uv_set},
    {TextureSlot::MetallicRoughness, "metallic_roughness_texture",
     "Multiplies roughness (G channel) and metallic (B channel); a linear data texture.",
     TextureColorSpace::Linear, 32, &Material::metallic_roughness_uv_set},
    {TextureSlot::Normal, "normal_texture",
     "A tangent-space normal map (glTF's convention: +Y up in texture space), scaled by "
     "normal_scale; a linear data texture. Needs the mesh's normals and uvs.",
     TextureColorSpace::Linear, 33, &Material::normal_uv_set},
    {TextureSlot::Occlusion, "occlusion_texture",
     "Ambient occlusion (R channel), applied with occlusion_strength to light arriving by "
     "bounces; a linear data texture.",
     TextureColorSpace::Linear, 34, &Material::occlusion_uv_set},
    {TextureSlot::Emissive, "emissive_texture",
     "Multiplies emission (RGB); an sRGB colour texture.", TextureColorSpace::Srgb, 35,
     &Material::emissive_uv_set},
};
static_assert(TEXTURE_SLOTS[0].slot == TextureSlot::BaseColor &&
              TEXTURE_SLOTS[1].slot == TextureSlot::MetallicRoughness &&
              TEXTURE_SLOTS[2].slot == TextureSlot::Normal &&
              TEXTURE_SLOTS[3].slot == TextureSlot::Occlusion &&
              TEXTURE_SLOTS[4].slot == TextureSlot::Emissive,
              "TEXTURE_SLOTS is indexed by TextureSlot");

/// Pinhole camera.
struct Camera {
    Vec3 eye{0.0f, 2.0f, 8.0f};
    Vec3 target{0.0f};
    Vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y_deg = 45.0f;
    /// The part of the frame the shutter is open for, in frame time (0 to 1, the span motion
    /// keys cover): each camera sample picks a time in [open, close]. Equal: no motion blur.
    float shutter_open = 0.0f;
    float shutter_close = 0.0f;

    friend bool operator==(const Camera&, const Camera&) = default;
};

/// Directional sun plus a uniform sky. `sun_direction` points from the scene toward the sun.
/// How motion keys are interpolated: linear blends every number of the matrices (rotations
/// shrink halfway); srt interpolates scale, skew and translation linearly and the rotation by
/// slerp (engine/core/srt.h), as Embree's quaternion keys.
enum class MotionInterpolation : uint8_t { Linear, Srt };

/// Between transforms `a` (u = 0) and `b` (u = 1), as `how` interpolates keys.
Affine interpolate(const Affine& a, const Affine& b, float u, MotionInterpolation how);

/// Transform keys evenly spaced over frame time [0, 1], interpolated at `time` as Embree
/// interpolates them; `keys` holds at least two.
Affine motion_at(const std::vector<Affine>& keys, float time,
                 MotionInterpolation how = MotionInterpolation::Linear);

/// One key of an instance's animation: its transform (relative to its parent, as `transform`)
/// at scene time `time`, in seconds (animation.h).
struct Keyframe {
    float time = 0.0f;
    Affine transform;

    friend bool operator==(const Keyframe&, const Keyframe&) = default;
};

/// Most keyframes one animation holds.
constexpr std::size_t MAX_ANIMATION_KEYS = 65536;
/// Scene times (the clock and keyframes) lie in [-MAX_SCENE_TIME, MAX_SCENE_TIME] seconds.
constexpr float MAX_SCENE_TIME = 1e7f;

/// The scene's clock: the time animations are evaluated at, and how long a frame lasts (the
/// scene time frame time 0 to 1 spans, so an animated instance blurs over it; animation.h).
struct Timeline {
    float time = 0.0f;
    float frame_duration = 1.0f / 24.0f;

    friend bool operator==(const Timeline&, const Timeline&) = default;
};

struct Lighting {
    Vec3 sun_direction{0.4f, 0.8f, 0.45f};
    Vec3 sun_color{1.0f, 0.95f, 0.9f};
    Vec3 sky_color{0.45f, 0.6f, 0.85f};
    float sky_intensity = 0.6f;

    friend bool operator==(const Lighting&, const Lighting&) = default;
};

enum class LightKind : uint8_t { Point, Spot, Rect };

const char* light_kind_name(LightKind k);

/// A light beyond the sun and sky, sampled by next-event estimation. Lights are not geometry:
/// rays do not hit them, and editing one touches no acceleration structure.
///
/// Units, as for the sun (shading.h): a point or spot light of `intensity` I and `color` c
/// delivers irradiance I * c / d^2 at distance d, like a sun of color I * c / (pi d^2). A rect
/// light emits radiance `intensity * color` from its front side (the side `direction` points to)
/// over a width x height rectangle centred at `position`; its width runs along
/// normalize(cross(W, direction)), W = +y, or +z when `direction` is within ~1 degree of +-y.
struct Light {
    LightKind kind = LightKind::Point;
    Vec3 position{0.0f, 3.0f, 0.0f};
    Vec3 direction{0.0f, -1.0f, 0.0f};  ///< spot axis, rect normal (any length but zero)
    Vec3 color{1.0f};
    float intensity = 10.0f;
    float angle_deg = 30.0f;        ///< spot: half-angle of the cone, (0, 90]
    float inner_angle_deg = 25.0f;  ///< spot: full intensity inside, fading to 0 at angle_deg
    float width = 1.0f;             ///< rect
    float height = 1.0f;            ///< rect
    std::string name = {};          ///< display name (object_fields.h)

    friend bool operator==(const Light&, const Light&) = default;
};

/// Checks a light: finite, colors and intensity >= 0, direction non-zero, angles and sizes in
/// range. The error names the field.
Status check_light(const Light& l);

/// Checks a camera: finite, eye != target, up not along the view, fov in (0, 180).
Status check_camera(const Camera& c);
/// Checks lighting: finite, non-zero sun direction, non-negative colors and intensity.
Status check_lighting(const Lighting& l);
/// Checks a material: finite, colors and factors in range. The error names the field.
Status check_material(const Material& m);

}  // namespace strata

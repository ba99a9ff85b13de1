#pragma once
// Plain scene value types: meshes, materials, camera and lighting.

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/math.h"
#include "engine/core/result.h"

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

/// Surface description. Colors are linear RGB. The base-colour texture itself is named by the
/// material's record (MaterialRecord::base_color_texture); its texels multiply `base_color`.
struct Material {
    Vec3 base_color{0.8f};
    float roughness = 0.5f;
    float metallic = 0.0f;
    Vec3 emission{0.0f};
    TextureSampler base_color_sampler = {};
    std::string name = {};  ///< display name (object_fields.h)

    friend bool operator==(const Material&, const Material&) = default;
};

/// Pinhole camera.
struct Camera {
    Vec3 eye{0.0f, 2.0f, 8.0f};
    Vec3 target{0.0f};
    Vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y_deg = 45.0f;

    friend bool operator==(const Camera&, const Camera&) = default;
};

/// Directional sun plus a uniform sky. `sun_direction` points from the scene toward the sun.
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

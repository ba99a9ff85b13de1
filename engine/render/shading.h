#pragma once
// Light transport pieces: the sky dome, the sun and the surface BRDF.
//
// BRDF: the glTF 2.0 metallic-roughness model. Lambert diffuse for the dielectric part plus a
// GGX microfacet specular lobe with height-correlated Smith visibility and Schlick Fresnel:
//   F0 = mix(0.04, base_color, metallic), alpha = roughness^2 (at least MIN_ALPHA),
//   f  = (1 - metallic) * (1 - F_schlick(0.04, v.h)) * base_color / pi
//        + D * Vis * F_schlick(F0, v.h).
//
// Light units: a white Lambertian surface facing the sun reflects radiance `sun_color` (the sun's
// irradiance is pi * sun_color), and under a uniform sky of radiance L it reflects L. So
// `base_color * (sun_color * cos + sky)` is what simple shading would give, and exposure 0 is
// about right for colors near 1.
//
// Sky dome radiance in direction d: sky_color * sky_intensity at the zenith, blending (by
// sqrt(d.y)) to a paler horizon, halfway between sky_color and white, times sky_intensity; below
// the horizon it fades to a dim ground at 30% of the horizon. The background of camera rays that
// miss everything is this gradient.

#include <algorithm>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata {

/// Smallest GGX alpha: keeps the sun's highlight on near-mirrors finite.
constexpr float MIN_ALPHA = 1e-3f;

/// Sky dome and sun of one frame.
class SkyModel {
public:
    explicit SkyModel(const Lighting& l);

    /// Radiance arriving from direction `dir` (unit, pointing away from the receiver).
    Vec3 radiance(const Vec3& dir) const;
    /// Unit vector toward the sun.
    const Vec3& sun_direction() const { return m_sun_dir; }
    /// Irradiance the sun delivers to a surface facing it: pi * sun_color.
    const Vec3& sun_irradiance() const { return m_sun_irradiance; }
    /// True when the sun contributes anything (non-zero color).
    bool has_sun() const { return m_has_sun; }

private:
    Vec3 m_zenith;
    Vec3 m_horizon;
    Vec3 m_ground;
    Vec3 m_sun_dir;
    Vec3 m_sun_irradiance;
    bool m_has_sun;
};

/// A direction drawn from the BRDF.
struct BsdfSample {
    Vec3 dir{0.0f};
    Vec3 weight{0.0f};  ///< f * cos / pdf
    float pdf = 0.0f;   ///< solid-angle density of `dir`
    bool valid = false;
};

/// The BRDF of one material at one shading point.
class Bsdf {
public:
    /// `min_roughness` regularises glossy lobes (for secondary surfaces).
    explicit Bsdf(const Material& m, float min_roughness = 0.0f);

    /// f(v, l) * max(n.l, 0); zero when either direction is below the surface. Unit vectors; `n`
    /// faces `v`.
    Vec3 eval_cos(const Vec3& n, const Vec3& v, const Vec3& l) const;

    /// Draws a reflected direction (one-sample MIS between a cosine-weighted diffuse lobe and GGX
    /// visible-normal sampling) from three uniform numbers.
    BsdfSample sample(const Vec3& n, const Vec3& v, float u0, float u1, float u_lobe) const;

    /// The solid-angle density with which sample() draws `l`. Unit vectors; `n` faces `v`.
    float pdf(const Vec3& n, const Vec3& v, const Vec3& l) const;

    const Vec3& base_color() const { return m_base; }

private:
    /// Probability of choosing the specular lobe at this view angle.
    float specular_probability(float n_dot_v) const;
    /// The mixture density of local direction `l` for local view `v` (both above the surface).
    float local_pdf(const Vec3& v, const Vec3& l, float p_spec) const;

    Vec3 m_base;
    Vec3 m_f0;
    float m_alpha;
    float m_metallic;
};

/// Scales `c` down so its largest component is at most `limit` (keeps the hue).
inline Vec3 clamp_max_component(const Vec3& c, float limit) {
    const float m = std::max(c.x, std::max(c.y, c.z));
    return m > limit ? c * (limit / m) : c;
}

}  // namespace strata

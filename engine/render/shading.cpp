#include "engine/render/shading.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace strata {

namespace {

constexpr float PI = std::numbers::pi_v<float>;
constexpr float INV_PI = std::numbers::inv_pi_v<float>;

/// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
struct Frame {
    Vec3 t, b, n;

    explicit Frame(const Vec3& normal) : n(normal) {
        const float sign = std::copysign(1.0f, n.z);
        const float a = -1.0f / (sign + n.z);
        const float bb = n.x * n.y * a;
        t = Vec3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
        b = Vec3(bb, sign + n.y * n.y * a, -n.y);
    }
    Vec3 to_local(const Vec3& v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

float schlick_weight(float cos_theta) {
    const float m = std::clamp(1.0f - cos_theta, 0.0f, 1.0f);
    const float m2 = m * m;
    return m2 * m2 * m;
}

/// GGX normal distribution for cos(n, h).
float ggx_d(float n_dot_h, float alpha) {
    const float a2 = alpha * alpha;
    const float d = n_dot_h * n_dot_h * (a2 - 1.0f) + 1.0f;
    return a2 / (PI * d * d);
}

/// Height-correlated Smith visibility G2 / (4 n.l n.v).
float smith_visibility(float n_dot_v, float n_dot_l, float alpha) {
    const float a2 = alpha * alpha;
    const float gv = n_dot_l * std::sqrt(n_dot_v * n_dot_v * (1.0f - a2) + a2);
    const float gl = n_dot_v * std::sqrt(n_dot_l * n_dot_l * (1.0f - a2) + a2);
    return 0.5f / (gv + gl);
}

/// Smith masking G1 for the view direction.
float smith_g1(float n_dot_v, float alpha) {
    const float a2 = alpha * alpha;
    return 2.0f * n_dot_v / (n_dot_v + std::sqrt(a2 + (1.0f - a2) * n_dot_v * n_dot_v));
}

/// A visible normal for local view direction `v` (Heitz 2018, "Sampling the GGX Distribution of
/// Visible Normals").
Vec3 sample_vndf(const Vec3& v, float alpha, float u0, float u1) {
    const Vec3 vh = glm::normalize(Vec3(alpha * v.x, alpha * v.y, v.z));
    const float len2 = vh.x * vh.x + vh.y * vh.y;
    const Vec3 t1 =
        len2 > 0.0f ? Vec3(-vh.y, vh.x, 0.0f) / std::sqrt(len2) : Vec3(1.0f, 0.0f, 0.0f);
    const Vec3 t2 = glm::cross(vh, t1);
    const float r = std::sqrt(u0);
    const float phi = 2.0f * PI * u1;
    const float p1 = r * std::cos(phi);
    float p2 = r * std::sin(phi);
    const float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
    const Vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
    return glm::normalize(Vec3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

/// Cosine-weighted direction around +z (concentric disk mapping, Shirley and Chiu).
Vec3 sample_cosine(float u0, float u1) {
    const float a = 2.0f * u0 - 1.0f, b = 2.0f * u1 - 1.0f;
    float r = 0.0f, phi = 0.0f;
    if (a != 0.0f || b != 0.0f) {
        if (std::abs(a) > std::abs(b)) {
            r = a;
            phi = (PI / 4.0f) * (b / a);
        } else {
            r = b;
            phi = (PI / 2.0f) - (PI / 4.0f) * (a / b);
        }
    }
    const float x = r * std::cos(phi), y = r * std::sin(phi);
    return {x, y, std::sqrt(std::max(0.0f, 1.0f - x * x - y * y))};
}

}  // namespace

SkyModel::SkyModel(const Lighting& l) {
    const Vec3 sky = l.sky_color * l.sky_intensity;
    m_zenith = sky;
    m_horizon = 0.5f * (l.sky_color + Vec3(1.0f)) * l.sky_intensity;
    m_ground = 0.3f * m_horizon;
    const float len = glm::length(l.sun_direction);
    m_sun_dir = len > 0.0f ? l.sun_direction / len : Vec3(0.0f, 1.0f, 0.0f);
    m_sun_irradiance = PI * l.sun_color;
    m_has_sun = l.sun_color.x > 0.0f || l.sun_color.y > 0.0f || l.sun_color.z > 0.0f;
}

Vec3 SkyModel::radiance(const Vec3& dir) const {
    if (dir.y >= 0.0f) return glm::mix(m_horizon, m_zenith, std::sqrt(dir.y));
    return glm::mix(m_horizon, m_ground, std::min(1.0f, -4.0f * dir.y));
}

Bsdf::Bsdf(const Material& m, float min_roughness)
    : m_base(m.base_color),
      m_f0(glm::mix(Vec3(0.04f), m.base_color, m.metallic)),
      m_alpha(std::max(std::max(m.roughness, min_roughness) * std::max(m.roughness, min_roughness),
                       MIN_ALPHA)),
      m_metallic(m.metallic) {}

Vec3 Bsdf::eval_cos(const Vec3& n, const Vec3& v, const Vec3& l) const {
    const float n_dot_l = glm::dot(n, l);
    const float n_dot_v = glm::dot(n, v);
    if (n_dot_l <= 0.0f || n_dot_v <= 0.0f) return Vec3(0.0f);
    const Vec3 h = glm::normalize(v + l);
    const float n_dot_h = std::max(0.0f, glm::dot(n, h));
    const float v_dot_h = std::max(0.0f, glm::dot(v, h));
    const float fw = schlick_weight(v_dot_h);
    const Vec3 fresnel = m_f0 + (Vec3(1.0f) - m_f0) * fw;
    const Vec3 specular =
        fresnel * (ggx_d(n_dot_h, m_alpha) * smith_visibility(n_dot_v, n_dot_l, m_alpha));
    const float dielectric_fresnel = 0.04f + 0.96f * fw;
    const Vec3 diffuse = m_base * ((1.0f - m_metallic) * (1.0f - dielectric_fresnel) * INV_PI);
    return (diffuse + specular) * n_dot_l;
}

float Bsdf::specular_probability(float n_dot_v) const {
    const float fw = schlick_weight(n_dot_v);
    const float specular = luminance(m_f0 + (Vec3(1.0f) - m_f0) * fw);
    const float diffuse = (1.0f - m_metallic) * luminance(m_base) * (1.0f - (0.04f + 0.96f * fw));
    if (specular + diffuse <= 0.0f) return 0.0f;
    return specular / (specular + diffuse);
}

BsdfSample Bsdf::sample(const Vec3& n, const Vec3& v, float u0, float u1, float u_lobe) const {
    BsdfSample out;
    const Frame frame(n);
    const Vec3 v_local = frame.to_local(v);
    if (v_local.z <= 0.0f) return out;
    const float p_spec = specular_probability(v_local.z);

    // Step: pick a lobe and draw a local direction from it.
    Vec3 l_local;
    if (u_lobe < p_spec) {
        const Vec3 h = sample_vndf(v_local, m_alpha, u0, u1);
        l_local = 2.0f * glm::dot(v_local, h) * h - v_local;
    } else {
        l_local = sample_cosine(u0, u1);
    }
    if (l_local.z <= 0.0f) return out;

    // Step: weight by the mixture pdf of both lobes (one-sample MIS, balance heuristic).
    const float pdf = local_pdf(v_local, l_local, p_spec);
    if (!(pdf > 0.0f)) return out;
    out.dir = glm::normalize(frame.to_world(l_local));
    out.weight = eval_cos(n, v, out.dir) / pdf;
    out.pdf = pdf;
    out.valid = is_finite(out.weight);
    return out;
}

float Bsdf::local_pdf(const Vec3& v, const Vec3& l, float p_spec) const {
    const Vec3 h = glm::normalize(v + l);
    const float pdf_spec = smith_g1(v.z, m_alpha) * ggx_d(std::max(0.0f, h.z), m_alpha) / (4.0f * v.z);
    const float pdf_diffuse = l.z * INV_PI;
    return p_spec * pdf_spec + (1.0f - p_spec) * pdf_diffuse;
}

float Bsdf::pdf(const Vec3& n, const Vec3& v, const Vec3& l) const {
    const Frame frame(n);
    const Vec3 v_local = frame.to_local(v);
    const Vec3 l_local = frame.to_local(l);
    if (v_local.z <= 0.0f || l_local.z <= 0.0f) return 0.0f;
    return local_pdf(v_local, l_local, specular_probability(v_local.z));
}

}  // namespace strata

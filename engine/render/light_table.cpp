#include "engine/render/light_table.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace strata {

namespace {

constexpr float PI = std::numbers::pi_v<float>;

float mean(const Vec3& c) {
    return (c.x + c.y + c.z) * (1.0f / 3.0f);
}

float radians(float deg) {
    return deg * (PI / 180.0f);
}

/// The width and height axes of a rect light facing `n` (unit): see Light in types.h.
void rect_axes(const Vec3& n, Vec3& u, Vec3& v) {
    const Vec3 w = std::abs(n.y) > 0.9998f ? Vec3(0.0f, 0.0f, 1.0f) : Vec3(0.0f, 1.0f, 0.0f);
    u = glm::normalize(glm::cross(w, n));
    v = glm::cross(n, u);
}

}  // namespace

float light_power(const Light& l) {
    const float c = mean(l.color) * l.intensity;
    switch (l.kind) {
        case LightKind::Point:
            return 4.0f * PI * c;
        case LightKind::Spot: {
            const float half = 0.5f * radians(l.angle_deg + l.inner_angle_deg);
            return 2.0f * PI * (1.0f - std::cos(half)) * c;
        }
        case LightKind::Rect:
            return PI * l.width * l.height * c;
    }
    return 0.0f;
}

float emitter_power(const Vec3& emission, float area) {
    return PI * area * mean(emission);
}

void LightTable::build(std::vector<Light> lights, std::vector<EmitterTriangle> emitters) {
    m_lights = std::move(lights);
    m_emitters = std::move(emitters);
    m_entries.clear();
    m_entries.reserve(m_lights.size() + m_emitters.size());
    // Summed in double: a million small triangles must not lose the last ones to rounding.
    double total = 0.0;
    auto add = [&](uint32_t index, float power) {
        if (!(power > 0.0f) || !std::isfinite(power)) return;
        total += power;
        m_entries.push_back({index, float(total)});
    };
    for (uint32_t i = 0; i < m_lights.size(); ++i) add(i, light_power(m_lights[i]));
    for (uint32_t i = 0; i < m_emitters.size(); ++i)
        add(uint32_t(m_lights.size()) + i,
            emitter_power(m_emitters[i].emission, m_emitters[i].area));
    m_total = float(total);
}

float LightTable::emitter_pdf(const Vec3& emission, float distance, float cos_light) const {
    if (empty() || !(cos_light > 0.0f)) return 0.0f;
    // (power / total) chooses the triangle, 1 / area the point on it: the area cancels.
    return PI * mean(emission) / m_total * distance * distance / cos_light;
}

LightSample LightTable::sample(const Vec3& p, float u_select, float u0, float u1) const {
    if (empty()) return {};
    const float target = u_select * m_total;
    auto it = std::upper_bound(m_entries.begin(), m_entries.end(), target,
                               [](float t, const Entry& e) { return t < e.cdf; });
    if (it == m_entries.end()) --it;
    const float before = it == m_entries.begin() ? 0.0f : std::prev(it)->cdf;
    const float p_select = (it->cdf - before) / m_total;
    if (!(p_select > 0.0f)) return {};
    LightSample s = it->index < m_lights.size()
                        ? sample_light(m_lights[it->index], p, u0, u1)
                        : sample_emitter(m_emitters[it->index - m_lights.size()], p, u0, u1);
    if (!s.valid) return s;
    s.weight /= p_select;
    s.pdf *= p_select;
    s.valid = is_finite(s.weight) && std::isfinite(s.pdf);
    return s;
}

LightSample LightTable::sample_light(const Light& l, const Vec3& p, float u0, float u1) const {
    LightSample s;
    const Vec3 axis = glm::normalize(l.direction);
    Vec3 q = l.position;
    if (l.kind == LightKind::Rect) {
        Vec3 u, v;
        rect_axes(axis, u, v);
        q += (u0 - 0.5f) * l.width * u + (u1 - 0.5f) * l.height * v;
    }
    const Vec3 to = q - p;
    const float d2 = glm::dot(to, to);
    if (!(d2 > 0.0f) || !std::isfinite(d2)) return s;
    s.distance = std::sqrt(d2);
    s.dir = to / s.distance;
    const Vec3 radiance = l.color * l.intensity;
    const float cos_axis = -glm::dot(s.dir, axis);  // at the light, toward the receiver
    switch (l.kind) {
        case LightKind::Point:
            s.weight = radiance / d2;
            break;
        case LightKind::Spot: {
            const float cos_outer = std::cos(radians(l.angle_deg));
            const float cos_inner = std::cos(radians(l.inner_angle_deg));
            float t = 1.0f;
            if (cos_inner > cos_outer)
                t = std::clamp((cos_axis - cos_outer) / (cos_inner - cos_outer), 0.0f, 1.0f);
            else
                t = cos_axis >= cos_outer ? 1.0f : 0.0f;
            s.weight = radiance * (t * t * (3.0f - 2.0f * t) / d2);
            break;
        }
        case LightKind::Rect:
            if (cos_axis <= 0.0f) return s;  // behind it: rect lights emit from the front
            s.weight = radiance * (cos_axis * l.width * l.height / d2);
            break;
    }
    s.valid = s.weight.x > 0.0f || s.weight.y > 0.0f || s.weight.z > 0.0f;
    return s;
}

LightSample LightTable::sample_emitter(const EmitterTriangle& t, const Vec3& p, float u0,
                                       float u1) const {
    LightSample s;
    // Uniform on the triangle (Shirley's square-root mapping).
    const float r = std::sqrt(u0);
    const Vec3 q = t.p0 + (r * (1.0f - u1)) * t.e1 + (r * u1) * t.e2;
    const Vec3 to = q - p;
    const float d2 = glm::dot(to, to);
    if (!(d2 > 0.0f) || !std::isfinite(d2)) return s;
    s.distance = std::sqrt(d2);
    s.dir = to / s.distance;
    const Vec3 n = glm::normalize(glm::cross(t.e1, t.e2));
    const float cos_light = std::abs(glm::dot(s.dir, n));
    if (!(cos_light > 1e-6f)) return s;
    s.weight = t.emission * (cos_light * t.area / d2);
    s.pdf = d2 / (cos_light * t.area);
    s.valid = true;
    return s;
}

}  // namespace strata

#include "engine/render/tangents.h"

#include <cmath>

namespace strata {

namespace {

/// The angle at corner `a` of triangle (a, b, c).
float corner_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 e1 = b - a, e2 = c - a;
    const float l = glm::length(e1) * glm::length(e2);
    if (!(l > 0.0f)) return 0.0f;
    return std::acos(glm::clamp(glm::dot(e1, e2) / l, -1.0f, 1.0f));
}

}  // namespace

Vec3 any_orthogonal(const Vec3& n) {
    const Vec3 axis = std::abs(n.x) < 0.9f ? Vec3(1.0f, 0.0f, 0.0f) : Vec3(0.0f, 1.0f, 0.0f);
    return glm::normalize(glm::cross(axis, n));
}

std::vector<glm::vec4> make_tangents(const std::vector<Vec3>& positions,
                                     const std::vector<Triangle>& triangles,
                                     const std::vector<Vec3>& normals,
                                     const std::vector<Vec2>& uvs) {
    const std::size_t n = positions.size();
    std::vector<Vec3> tangent(n, Vec3(0.0f));
    std::vector<float> handedness(n, 0.0f);
    for (const Triangle& t : triangles) {
        const Vec3 p[3] = {positions[t[0]], positions[t[1]], positions[t[2]]};
        const Vec2 uv[3] = {uvs[t[0]], uvs[t[1]], uvs[t[2]]};
        const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
        const Vec2 d1 = uv[1] - uv[0], d2 = uv[2] - uv[0];
        const float det = d1.x * d2.y - d2.x * d1.y;
        if (!(std::abs(det) > 1e-20f) || !std::isfinite(det)) continue;
        // dP/du and dP/dv of the triangle's affine map from uv to position.
        Vec3 dpdu = (e1 * d2.y - e2 * d1.y) / det;
        Vec3 dpdv = (e2 * d1.x - e1 * d2.x) / det;
        const float lu = glm::length(dpdu);
        if (!(lu > 0.0f) || !std::isfinite(lu) || !is_finite(dpdv)) continue;
        dpdu /= lu;
        for (int c = 0; c < 3; ++c) {
            const float w = corner_angle(p[c], p[(c + 1) % 3], p[(c + 2) % 3]);
            tangent[t[c]] += w * dpdu;
            // The bitangent cross(n, t) should point against dP/dv (where v falls).
            const float side = glm::dot(glm::cross(normals[t[c]], dpdu), dpdv);
            handedness[t[c]] += side <= 0.0f ? w : -w;
        }
    }
    std::vector<glm::vec4> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        Vec3 nrm = normals[i];
        const float ln = glm::length(nrm);
        nrm = ln > 0.0f && std::isfinite(ln) ? nrm / ln : Vec3(0.0f, 0.0f, 1.0f);
        Vec3 t = tangent[i] - nrm * glm::dot(nrm, tangent[i]);
        const float lt = glm::length(t);
        t = lt > 1e-12f && std::isfinite(lt) ? t / lt : any_orthogonal(nrm);
        out[i] = glm::vec4(t, handedness[i] < 0.0f ? -1.0f : 1.0f);
    }
    return out;
}

}  // namespace strata

#include "engine/core/srt.h"

#include <cmath>

namespace strata {

SrtParts decompose_srt(const Affine& a) {
    // Gram-Schmidt on the columns of the linear part: L = Q U, Q a rotation, U upper triangular.
    const Vec3 c0(a.at(0, 0), a.at(1, 0), a.at(2, 0));
    const Vec3 c1(a.at(0, 1), a.at(1, 1), a.at(2, 1));
    const Vec3 c2(a.at(0, 2), a.at(1, 2), a.at(2, 2));
    SrtParts p;
    p.scale.x = glm::length(c0);
    const Vec3 q0 = c0 / p.scale.x;
    p.skew.x = glm::dot(q0, c1);
    const Vec3 r1 = c1 - p.skew.x * q0;
    p.scale.y = glm::length(r1);
    const Vec3 q1 = r1 / p.scale.y;
    p.skew.y = glm::dot(q0, c2);
    p.skew.z = glm::dot(q1, c2);
    const Vec3 r2 = c2 - p.skew.y * q0 - p.skew.z * q1;
    p.scale.z = glm::length(r2);
    Vec3 q2 = r2 / p.scale.z;
    if (glm::dot(glm::cross(q0, q1), q2) < 0.0f) {  // a mirror: Q stays a rotation
        q2 = -q2;
        p.scale.z = -p.scale.z;
    }
    p.rotation = glm::normalize(glm::quat_cast(glm::mat3(q0, q1, q2)));
    p.translation = Vec3(a.at(0, 3), a.at(1, 3), a.at(2, 3));
    return p;
}

Affine compose_srt(const SrtParts& p) {
    const glm::mat3 r = glm::mat3_cast(p.rotation);
    const glm::mat3 s(Vec3(p.scale.x, 0.0f, 0.0f), Vec3(p.skew.x, p.scale.y, 0.0f),
                      Vec3(p.skew.y, p.skew.z, p.scale.z));
    const glm::mat3 l = r * s;
    Affine out;
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) out.at(row, col) = l[col][row];
        out.at(row, 3) = p.translation[row];
    }
    return out;
}

std::vector<SrtParts> srt_keys(const std::vector<Affine>& keys) {
    std::vector<SrtParts> out;
    out.reserve(keys.size());
    for (const Affine& k : keys) {
        SrtParts p = decompose_srt(k);
        if (!out.empty() && glm::dot(out.back().rotation, p.rotation) < 0.0f)
            p.rotation = -p.rotation;
        out.push_back(p);
    }
    return out;
}

Affine srt_lerp(const SrtParts& a, const SrtParts& b, float t) {
    SrtParts p;
    p.scale = glm::mix(a.scale, b.scale, t);
    p.skew = glm::mix(a.skew, b.skew, t);
    p.translation = glm::mix(a.translation, b.translation, t);
    p.rotation = glm::slerp(a.rotation, b.rotation, t);
    return compose_srt(p);
}

}  // namespace strata

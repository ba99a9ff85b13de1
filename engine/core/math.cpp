#include "engine/core/math.h"

#include <algorithm>

namespace strata {

Affine Affine::translation(const Vec3& t) {
    Affine a;
    a.m[3] = t.x;
    a.m[7] = t.y;
    a.m[11] = t.z;
    return a;
}

Affine Affine::scaling(const Vec3& s) {
    Affine a;
    a.m[0] = s.x;
    a.m[5] = s.y;
    a.m[10] = s.z;
    return a;
}

Affine Affine::rotation_euler_deg(const Vec3& deg) {
    const Vec3 r = glm::radians(deg);
    const float cx = std::cos(r.x), sx = std::sin(r.x);
    const float cy = std::cos(r.y), sy = std::sin(r.y);
    const float cz = std::cos(r.z), sz = std::sin(r.z);
    Affine rx, ry, rz;
    rx.m = {1, 0, 0, 0, 0, cx, -sx, 0, 0, sx, cx, 0};
    ry.m = {cy, 0, sy, 0, 0, 1, 0, 0, -sy, 0, cy, 0};
    rz.m = {cz, -sz, 0, 0, sz, cz, 0, 0, 0, 0, 1, 0};
    return rz * ry * rx;
}

Affine Affine::rotation_quaternion(const Vec4& q_in) {
    // In double: the squared length of a float quaternion overflows a float beyond ~1.8e19 and
    // underflows below ~1e-19, and either would silently normalise to a wrong rotation.
    const glm::dvec4 qd(q_in);
    const double len = std::sqrt(glm::dot(qd, qd));
    const Vec4 q = len > 0.0 && std::isfinite(len) ? Vec4(qd / len) : Vec4(0, 0, 0, 1);
    const float x = q.x, y = q.y, z = q.z, w = q.w;
    Affine a;
    a.m = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),     0,
           2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),     0,
           2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y), 0};
    return a;
}

Affine Affine::trs(const Vec3& t, const Affine& r, const Vec3& s) {
    return translation(t) * r * scaling(s);
}

Vec3 Affine::transform_point(const Vec3& p) const {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

Vec3 Affine::transform_vector(const Vec3& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
}

float Affine::determinant() const {
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

Affine Affine::inverse() const {
    const glm::dmat3 lin(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]);  // column-major
    const glm::dmat3 inv = glm::inverse(lin);
    const glm::dvec3 t(m[3], m[7], m[11]);
    const glm::dvec3 it = -(inv * t);
    Affine a;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) a.at(r, c) = static_cast<float>(inv[c][r]);
        a.at(r, 3) = static_cast<float>(it[r]);
    }
    return a;
}

Affine Affine::operator*(const Affine& o) const {
    Affine out;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) {
            float v = at(r, 0) * o.at(0, c) + at(r, 1) * o.at(1, c) + at(r, 2) * o.at(2, c);
            if (c == 3) v += at(r, 3);
            out.at(r, c) = v;
        }
    }
    return out;
}

Affine Affine::lerp(const Affine& a, const Affine& b, float t) {
    Affine out;
    for (std::size_t k = 0; k < out.m.size(); ++k) out.m[k] = (1.0f - t) * a.m[k] + t * b.m[k];
    return out;
}

glm::mat3 Affine::normal_matrix() const {
    const glm::mat3 lin(m[0], m[4], m[8], m[1], m[5], m[9], m[2], m[6], m[10]);
    return glm::transpose(glm::inverse(lin));
}

bool Affine::is_finite() const {
    return std::all_of(m.begin(), m.end(), [](float v) { return std::isfinite(v); });
}

Bounds3 Affine::transform_bounds(const Bounds3& b) const {
    Bounds3 out;
    if (b.empty()) return out;
    for (int i = 0; i < 8; ++i) {
        const Vec3 corner((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y,
                          (i & 4) ? b.upper.z : b.lower.z);
        out.extend(transform_point(corner));
    }
    return out;
}

std::array<float, 16> Affine::to_rows16() const {
    return {m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11], 0, 0, 0, 1};
}

const char* transform_problem(const Affine& t) {
    if (!t.is_finite()) return "transform has a NaN or infinite element";
    for (int r = 0; r < 3; ++r) {
        if (std::abs(double(t.at(r, 3))) > MAX_COORDINATE)
            return "transform translates beyond 1e15 (rays there would be refused)";
    }
    double lengths[3];
    for (int c = 0; c < 3; ++c) {
        const double x = t.at(0, c), y = t.at(1, c), z = t.at(2, c);
        lengths[c] = std::sqrt(x * x + y * y + z * z);
        if (lengths[c] < MIN_AXIS_SCALE) return "transform is singular (an axis is scaled to zero)";
        if (lengths[c] > MAX_AXIS_SCALE) return "transform scales an axis beyond 1e6";
    }
    const double shortest = std::min({lengths[0], lengths[1], lengths[2]});
    const double longest = std::max({lengths[0], lengths[1], lengths[2]});
    if (shortest < MAX_ANISOTROPY_INV * longest)
        return "transform is degenerate (axis scales differ by more than 1e6)";
    // |det| against the product of the axis lengths (Hadamard's bound): 1 for an orthogonal
    // basis, 0 when the axes are coplanar, whatever the overall scale.
    const double det = t.determinant();
    if (std::abs(det) < 1e-6 * lengths[0] * lengths[1] * lengths[2])
        return "transform is singular or degenerate (its axes are nearly coplanar)";
    // What the renderer computes from it (normals, object-space rays) must be finite too.
    if (!t.inverse().is_finite()) return "transform has no finite inverse";
    return nullptr;
}

}  // namespace strata

#pragma once
// Pinhole ray generation. Ray directions are unit length, so a hit's t is the distance along the
// camera ray.

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "engine/scene/types.h"

namespace strata {

/// OpenEXR's worldToCamera for `c` (ImfStandardAttributes.h): camera space is left-handed with
/// the eye at the origin, x to the right of the image, y up and z along the view, as the rays
/// below use them. A glm (column-vector) matrix; its memory layout is Imath's row-vector M44f.
inline glm::mat4 world_to_camera(const Camera& c) {
    const Vec3 forward = glm::normalize(c.target - c.eye);
    const Vec3 right = glm::normalize(glm::cross(forward, c.up));
    const Vec3 up = glm::cross(right, forward);
    glm::mat4 m(1.0f);
    for (int k = 0; k < 3; ++k) {
        m[k][0] = right[k];
        m[k][1] = up[k];
        m[k][2] = forward[k];
    }
    m[3] = glm::vec4(-glm::dot(right, c.eye), -glm::dot(up, c.eye), -glm::dot(forward, c.eye), 1);
    return m;
}

/// OpenEXR's worldToNDC for `c` and a width x height image: after the divide by w, x runs from 0
/// at the image's left edge to 1 at its right and y from 0 at the top to 1 at the bottom, so
/// pixel (px, py)'s centre is ((px + 0.5) / width, (py + 0.5) / height). z (which the convention
/// discards) comes out as 1 / camera-space z, which keeps the matrix invertible.
inline glm::mat4 world_to_ndc(const Camera& c, uint32_t width, uint32_t height) {
    const float tan_half = std::tan(glm::radians(c.fov_y_deg) * 0.5f);
    const float aspect = float(width) / float(height);
    glm::mat4 p(0.0f);  // camera (x, y, z, 1) -> (x', y', 1, z)
    p[0][0] = 0.5f / (tan_half * aspect);
    p[1][1] = -0.5f / tan_half;
    p[2][0] = 0.5f;
    p[2][1] = 0.5f;
    p[2][3] = 1.0f;
    p[3][2] = 1.0f;
    return p * world_to_camera(c);
}

class CameraRays {
public:
    CameraRays(const Camera& c, uint32_t width, uint32_t height)
        : m_eye(c.eye), m_shutter_open(c.shutter_open), m_shutter_close(c.shutter_close) {
        const Vec3 forward = glm::normalize(c.target - c.eye);
        const Vec3 right = glm::normalize(glm::cross(forward, c.up));
        const Vec3 up = glm::cross(right, forward);
        const float tan_half = std::tan(glm::radians(c.fov_y_deg) * 0.5f);
        const float aspect = float(width) / float(height);
        m_right = right * (2.0f * tan_half * aspect / float(width));
        m_up = up * (-2.0f * tan_half / float(height));
        // Direction through pixel (px, py) is forward + (px - w/2) * right' + (py - h/2) * up'.
        m_origin_offset = forward - right * (tan_half * aspect) + up * tan_half;
    }

    const Vec3& eye() const { return m_eye; }
    /// The ray time of shutter position `u` in [0, 1]: from shutter_open to shutter_close.
    float time(float u) const { return m_shutter_open + (m_shutter_close - m_shutter_open) * u; }
    /// Whether the shutter stays open for a while (the frame has motion blur if anything moves).
    bool blurs() const { return m_shutter_close > m_shutter_open; }

    /// Unit direction through image position (x, y) in pixels; (0.5, 0.5) is the first pixel's
    /// centre.
    Vec3 direction(float x, float y) const {
        return glm::normalize(m_origin_offset + x * m_right + y * m_up);
    }

    /// direction(x[i], y[i]) for n lanes into structure-of-arrays outputs: the same arithmetic in
    /// the same order (so the same bits), in a loop the compiler vectorises.
    void directions(const float* x, const float* y, uint32_t n, float* dx, float* dy,
                    float* dz) const {
        const Vec3 o = m_origin_offset, r = m_right, u = m_up;  // locals: no aliasing with outputs
        for (uint32_t i = 0; i < n; ++i) {
            const float vx = (o.x + x[i] * r.x) + y[i] * u.x;
            const float vy = (o.y + x[i] * r.y) + y[i] * u.y;
            const float vz = (o.z + x[i] * r.z) + y[i] * u.z;
            const float inv = 1.0f / std::sqrt((vx * vx + vy * vy) + vz * vz);
            dx[i] = vx * inv;
            dy[i] = vy * inv;
            dz[i] = vz * inv;
        }
    }

private:
    Vec3 m_eye;
    float m_shutter_open;
    float m_shutter_close;
    Vec3 m_right;
    Vec3 m_up;
    Vec3 m_origin_offset;
};

}  // namespace strata

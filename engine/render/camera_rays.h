#pragma once
// Pinhole ray generation. Ray directions are unit length, so a hit's t is the distance along the
// camera ray.

#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "engine/scene/types.h"

namespace strata {

class CameraRays {
public:
    CameraRays(const Camera& c, uint32_t width, uint32_t height) : m_eye(c.eye) {
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

    /// Unit direction through image position (x, y) in pixels; (0.5, 0.5) is the first pixel's
    /// centre.
    Vec3 direction(float x, float y) const {
        return glm::normalize(m_origin_offset + x * m_right + y * m_up);
    }

private:
    Vec3 m_eye;
    Vec3 m_right;
    Vec3 m_up;
    Vec3 m_origin_offset;
};

}  // namespace strata

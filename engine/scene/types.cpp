#include "engine/scene/types.h"

#include <cmath>

namespace strata {

const char* build_preference_name(BuildPreference p) {
    return p == BuildPreference::FastTrace ? "fast_trace" : "fast_build";
}

namespace {

Status bad(ErrorCode code, const char* field, const char* message) {
    return failure(code, message, field);
}

bool in_unit_range(float v) {
    return v >= 0.0f && v <= 1.0f;
}

}  // namespace

Status check_camera(const Camera& c) {
    if (!is_finite(c.eye))
        return bad(ErrorCode::NotFinite, "eye", "eye has a NaN or infinite value");
    if (!is_finite(c.target))
        return bad(ErrorCode::NotFinite, "target", "target has a NaN or infinite value");
    if (!is_finite(c.up)) return bad(ErrorCode::NotFinite, "up", "up has a NaN or infinite value");
    if (!std::isfinite(c.fov_y_deg))
        return bad(ErrorCode::NotFinite, "fov_y_deg", "fov_y_deg is NaN or infinite");
    if (!(c.fov_y_deg > 0.0f && c.fov_y_deg < 180.0f))
        return bad(ErrorCode::InvalidArgument, "fov_y_deg", "fov_y_deg must be in (0, 180)");
    const Vec3 view = c.target - c.eye;
    const float view_len = glm::length(view);
    if (!(view_len > 1e-12f))
        return bad(ErrorCode::InvalidArgument, "target", "eye and target coincide");
    const float up_len = glm::length(c.up);
    if (!(up_len > 1e-12f)) return bad(ErrorCode::InvalidArgument, "up", "up has zero length");
    if (glm::length(glm::cross(view / view_len, c.up / up_len)) < 1e-4f)
        return bad(ErrorCode::InvalidArgument, "up", "up is parallel to the viewing direction");
    return {};
}

Status check_lighting(const Lighting& l) {
    const struct {
        const char* field;
        Vec3 value;
        bool colour;
    } vectors[] = {{"sun_direction", l.sun_direction, false},
                   {"sun_color", l.sun_color, true},
                   {"sky_color", l.sky_color, true}};
    for (const auto& v : vectors) {
        if (!is_finite(v.value))
            return bad(ErrorCode::NotFinite, v.field, "value has a NaN or infinite component");
        if (v.colour && glm::any(glm::lessThan(v.value, Vec3(0.0f))))
            return bad(ErrorCode::InvalidArgument, v.field, "color components must be >= 0");
    }
    if (!(glm::length(l.sun_direction) > 1e-12f))
        return bad(ErrorCode::InvalidArgument, "sun_direction", "sun_direction has zero length");
    if (!std::isfinite(l.sky_intensity))
        return bad(ErrorCode::NotFinite, "sky_intensity", "sky_intensity is NaN or infinite");
    if (l.sky_intensity < 0.0f)
        return bad(ErrorCode::InvalidArgument, "sky_intensity", "sky_intensity must be >= 0");
    return {};
}

Status check_material(const Material& m) {
    if (!is_finite(m.base_color))
        return bad(ErrorCode::NotFinite, "base_color",
                   "base_color has a NaN or infinite component");
    if (!in_unit_range(m.base_color.x) || !in_unit_range(m.base_color.y) ||
        !in_unit_range(m.base_color.z))
        return bad(ErrorCode::InvalidArgument, "base_color",
                   "base_color components must be in [0, 1]");
    if (!std::isfinite(m.roughness))
        return bad(ErrorCode::NotFinite, "roughness", "roughness is NaN or infinite");
    if (!in_unit_range(m.roughness))
        return bad(ErrorCode::InvalidArgument, "roughness", "roughness must be in [0, 1]");
    if (!std::isfinite(m.metallic))
        return bad(ErrorCode::NotFinite, "metallic", "metallic is NaN or infinite");
    if (!in_unit_range(m.metallic))
        return bad(ErrorCode::InvalidArgument, "metallic", "metallic must be in [0, 1]");
    if (!is_finite(m.emission))
        return bad(ErrorCode::NotFinite, "emission", "emission has a NaN or infinite component");
    if (glm::any(glm::lessThan(m.emission, Vec3(0.0f))))
        return bad(ErrorCode::InvalidArgument, "emission", "emission components must be >= 0");
    return {};
}

}  // namespace strata

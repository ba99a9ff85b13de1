#include "engine/scene/types.h"

#include <cmath>

namespace strata {

const char* build_preference_name(BuildPreference p) {
    return p == BuildPreference::FastTrace ? "fast_trace" : "fast_build";
}

const char* texture_wrap_name(TextureWrap w) {
    switch (w) {
        case TextureWrap::Clamp: return "clamp";
        case TextureWrap::Mirror: return "mirror";
        default: return "repeat";
    }
}

const char* texture_filter_name(TextureFilter f) {
    return f == TextureFilter::Nearest ? "nearest" : "bilinear";
}

namespace {

Status bad(ErrorCode code, const char* field, const char* message) {
    return failure(code, message, field);
}

bool in_unit_range(float v) {
    return v >= 0.0f && v <= 1.0f;
}

/// True when every component's magnitude is at most `limit` (NaN is not).
bool within(const Vec3& v, double limit) {
    return std::abs(double(v.x)) <= limit && std::abs(double(v.y)) <= limit &&
           std::abs(double(v.z)) <= limit;
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
    // Validate what is computed from the numbers, not only the numbers: finite values can still
    // overflow (eye and target at -3e38 and 3e38 give an infinite view vector) or put the
    // rays' origin where Embree refuses rays. Hence a range, then the basis in double.
    if (!within(c.eye, MAX_COORDINATE))
        return bad(ErrorCode::InvalidArgument, "eye", "eye is farther than 1e15 from the origin");
    if (!within(c.target, MAX_COORDINATE))
        return bad(ErrorCode::InvalidArgument, "target",
                   "target is farther than 1e15 from the origin");
    const glm::dvec3 view = glm::dvec3(c.target) - glm::dvec3(c.eye);
    const double view_len = glm::length(view);
    if (!(view_len > 1e-12))
        return bad(ErrorCode::InvalidArgument, "target", "eye and target coincide");
    const glm::dvec3 up(c.up);
    const double up_len = glm::length(up);
    if (!(up_len > 1e-12) || !std::isfinite(up_len))
        return bad(ErrorCode::InvalidArgument, "up", "up has zero or overflowing length");
    const glm::dvec3 side = glm::cross(view / view_len, up / up_len);
    if (!(glm::length(side) >= 1e-4))
        return bad(ErrorCode::InvalidArgument, "up", "up is parallel to the viewing direction");
    // The basis the camera rays are built from, in the precision they use.
    const Vec3 forward(view / view_len);
    const Vec3 right(side / glm::length(side));
    if (!is_finite(forward) || !is_finite(right) || !(glm::length(forward) > 0.5f))
        return bad(ErrorCode::InvalidArgument, "target",
                   "the viewing direction cannot be represented");
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

const char* light_kind_name(LightKind k) {
    switch (k) {
        case LightKind::Point: return "point";
        case LightKind::Spot: return "spot";
        case LightKind::Rect: return "rect";
    }
    return "point";
}

/// Largest light intensity and rect side accepted: far beyond any sensible scene, small enough
/// that products of them stay finite in float.
constexpr float MAX_LIGHT_INTENSITY = 1e12f;
constexpr float MAX_LIGHT_SIZE = 1e6f;

Status check_light(const Light& l) {
    if (!is_finite(l.position))
        return bad(ErrorCode::NotFinite, "position", "position has a NaN or infinite component");
    if (!within(l.position, MAX_COORDINATE))
        return bad(ErrorCode::InvalidArgument, "position",
                   "position is farther than 1e15 from the origin");
    if (!is_finite(l.direction))
        return bad(ErrorCode::NotFinite, "direction",
                   "direction has a NaN or infinite component");
    const glm::dvec3 d(l.direction);
    if (!(glm::dot(d, d) > 1e-24))
        return bad(ErrorCode::InvalidArgument, "direction", "direction has zero length");
    if (!is_finite(l.color))
        return bad(ErrorCode::NotFinite, "color", "color has a NaN or infinite component");
    if (glm::any(glm::lessThan(l.color, Vec3(0.0f))))
        return bad(ErrorCode::InvalidArgument, "color", "color components must be >= 0");
    if (!std::isfinite(l.intensity))
        return bad(ErrorCode::NotFinite, "intensity", "intensity is NaN or infinite");
    if (!(l.intensity >= 0.0f && l.intensity <= MAX_LIGHT_INTENSITY))
        return bad(ErrorCode::InvalidArgument, "intensity", "intensity must be in [0, 1e12]");
    if (!std::isfinite(l.angle_deg))
        return bad(ErrorCode::NotFinite, "angle_deg", "angle_deg is NaN or infinite");
    if (!(l.angle_deg > 0.0f && l.angle_deg <= 90.0f))
        return bad(ErrorCode::InvalidArgument, "angle_deg", "angle_deg must be in (0, 90]");
    if (!std::isfinite(l.inner_angle_deg))
        return bad(ErrorCode::NotFinite, "inner_angle_deg", "inner_angle_deg is NaN or infinite");
    if (!(l.inner_angle_deg >= 0.0f && l.inner_angle_deg <= l.angle_deg))
        return bad(ErrorCode::InvalidArgument, "inner_angle_deg",
                   "inner_angle_deg must be in [0, angle_deg]");
    for (const auto& [field, v] : {std::pair{"width", l.width}, std::pair{"height", l.height}}) {
        if (!std::isfinite(v))
            return bad(ErrorCode::NotFinite, field, "size is NaN or infinite");
        if (!(v > 0.0f && v <= MAX_LIGHT_SIZE))
            return failure(ErrorCode::InvalidArgument,
                           std::string(field) + " must be in (0, 1e6]", field);
    }
    return {};
}

}  // namespace strata

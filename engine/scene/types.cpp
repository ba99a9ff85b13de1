#include "engine/scene/types.h"

#include <algorithm>
#include <cmath>

#include "engine/core/srt.h"
#include "engine/scene/object_fields.h"

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

}  // namespace

Status check_camera(const Camera& c) {
    if (Status s = check_fields<CameraFields>(c); !s) return s;
    if (c.shutter_close < c.shutter_open)
        return bad(ErrorCode::InvalidArgument, "shutter_close",
                   "the shutter closes before it opens");
    // Validate what is computed from the numbers, not only the numbers: finite values within
    // range can still give a basis that does not come out finite. Hence the basis in double.
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
    if (Status s = check_fields<LightingFields>(l); !s) return s;
    if (!(glm::length(l.sun_direction) > 1e-12f))
        return bad(ErrorCode::InvalidArgument, "sun_direction", "sun_direction has zero length");
    return {};
}

Status check_material(const Material& m) {
    return check_fields<MaterialFields>(m);
}

const char* alpha_mode_name(AlphaMode m) {
    switch (m) {
        case AlphaMode::Opaque: return "opaque";
        case AlphaMode::Mask: return "mask";
        case AlphaMode::Blend: return "blend";
    }
    return "opaque";
}

Affine motion_at(const std::vector<Affine>& keys, float time, MotionInterpolation how) {
    const float f = std::clamp(time, 0.0f, 1.0f) * float(keys.size() - 1);
    const auto k = std::min(static_cast<std::size_t>(f), keys.size() - 2);
    return interpolate(keys[k], keys[k + 1], f - float(k), how);
}

Affine interpolate(const Affine& a, const Affine& b, float u, MotionInterpolation how) {
    if (how == MotionInterpolation::Linear) return Affine::lerp(a, b, u);
    const std::vector<SrtParts> pair = srt_keys({a, b});
    return srt_lerp(pair[0], pair[1], u);
}

const char* light_kind_name(LightKind k) {
    switch (k) {
        case LightKind::Point: return "point";
        case LightKind::Spot: return "spot";
        case LightKind::Rect: return "rect";
    }
    return "point";
}

Status check_light(const Light& l) {
    if (Status s = check_fields<LightFields>(l); !s) return s;
    const glm::dvec3 d(l.direction);
    if (!(glm::dot(d, d) > 1e-24))
        return bad(ErrorCode::InvalidArgument, "direction", "direction has zero length");
    if (!(l.inner_angle_deg <= l.angle_deg))
        return bad(ErrorCode::InvalidArgument, "inner_angle_deg",
                   "inner_angle_deg must be in [0, angle_deg]");
    return {};
}

}  // namespace strata

#include "engine/scene/field_table.h"

#include <cmath>
#include <cstdio>

#include "engine/core/utf8.h"

namespace strata {

std::string number_text(double v) {
    char buf[32];
    if (std::abs(v) >= 1e6 && std::abs(v) == std::floor(std::abs(v))) {
        const int exponent = int(std::floor(std::log10(std::abs(v))));
        const double mantissa = v / std::pow(10.0, exponent);
        if (mantissa == std::floor(mantissa)) {
            std::snprintf(buf, sizeof buf, "%ge%d", mantissa, exponent);
            return buf;
        }
    }
    std::snprintf(buf, sizeof buf, "%.10g", v);
    return buf;
}

namespace {

Status refuse(ErrorCode code, const FieldInfo& info, const std::string& why) {
    return failure(code, std::string(info.name) + " " + why, std::string(info.name));
}

}  // namespace

std::string limits_phrase(const Limits& l) {
    return (l.has_lo() && l.has_hi() ? "in " : "") + limits_text(l);
}

std::string limits_text(const Limits& l) {
    if (!l.has_hi()) return std::string(l.lo_open ? "> " : ">= ") + number_text(l.lo);
    if (!l.has_lo()) return std::string(l.hi_open ? "< " : "<= ") + number_text(l.hi);
    return std::string(l.lo_open ? "(" : "[") + number_text(l.lo) + ", " + number_text(l.hi) +
           (l.hi_open ? ")" : "]");
}

Status refuse_number(const FieldInfo& info, float v) {
    if (!std::isfinite(v)) return refuse(ErrorCode::NotFinite, info, "is NaN or infinite");
    return refuse(ErrorCode::InvalidArgument, info, "must be " + limits_phrase(info.limits));
}

Status refuse_vector(const FieldInfo& info, const Vec3& v) {
    if (!is_finite(v)) return refuse(ErrorCode::NotFinite, info, "has a NaN or infinite component");
    for (int i = 0; i < 3; ++i) {
        if (!info.limits.contains(v[i]))
            return refuse(ErrorCode::InvalidArgument, info,
                          "components must be " + limits_phrase(info.limits));
    }
    return {};
}

Status check_text(const FieldInfo& info, const std::string& v) {
    const double max = info.limits.has_hi() ? info.limits.hi : double(MAX_NAME_BYTES);
    if (const char* why = text_problem(v, std::size_t(max)))
        return refuse(
            ErrorCode::InvalidArgument, info,
            std::string(why) + (v.size() > max ? " (at most " + number_text(max) + " bytes)" : ""));
    return {};
}

Status check_value(const FieldInfo& info, const Affine& t) {
    if (const char* why = transform_problem(t))
        return failure(t.is_finite() ? ErrorCode::DegenerateTransform : ErrorCode::NotFinite, why,
                       std::string(info.name));
    return {};
}

bool value_ok(const FieldInfo&, const std::vector<Affine>& keys) {
    if (keys.size() == 1 || keys.size() > MAX_MOTION_KEYS) return false;
    for (const Affine& k : keys)
        if (transform_problem(k)) return false;
    return true;
}

Status check_value(const FieldInfo& info, const std::vector<Affine>& keys) {
    const std::string field(info.name);
    if (keys.size() == 1 || keys.size() > MAX_MOTION_KEYS)
        return failure(ErrorCode::InvalidArgument,
                       field + " has " + std::to_string(keys.size()) + " keys: give none or 2 to " +
                           std::to_string(MAX_MOTION_KEYS),
                       field);
    for (std::size_t k = 0; k < keys.size(); ++k) {
        if (const char* why = transform_problem(keys[k]))
            return failure(keys[k].is_finite() ? ErrorCode::DegenerateTransform
                                               : ErrorCode::NotFinite,
                           "key " + std::to_string(k) + ": " + why,
                           field + "/" + std::to_string(k));
    }
    return {};
}

Status check_value(const FieldInfo& info, const std::vector<Keyframe>& keys) {
    const std::string field(info.name);
    if (keys.size() > MAX_ANIMATION_KEYS)
        return failure(ErrorCode::TooLarge,
                       field + " has " + std::to_string(keys.size()) + " keys: at most " +
                           std::to_string(MAX_ANIMATION_KEYS),
                       field);
    for (std::size_t k = 0; k < keys.size(); ++k) {
        const std::string at = field + "/" + std::to_string(k);
        const float t = keys[k].time;
        if (!std::isfinite(t))
            return failure(ErrorCode::NotFinite, "key " + std::to_string(k) + ": time is NaN or "
                           "infinite", at + "/time");
        if (!(std::abs(t) <= MAX_SCENE_TIME))
            return failure(ErrorCode::InvalidArgument,
                           "key " + std::to_string(k) + ": time must be in [-" +
                               number_text(MAX_SCENE_TIME) + ", " + number_text(MAX_SCENE_TIME) +
                               "]",
                           at + "/time");
        if (k > 0 && !(t > keys[k - 1].time))
            return failure(ErrorCode::InvalidArgument,
                           "key " + std::to_string(k) + ": times must increase (" +
                               number_text(t) + " follows " + number_text(keys[k - 1].time) + ")",
                           at + "/time");
        if (const char* why = transform_problem(keys[k].transform))
            return failure(keys[k].transform.is_finite() ? ErrorCode::DegenerateTransform
                                                         : ErrorCode::NotFinite,
                           "key " + std::to_string(k) + ": " + why, at + "/transform");
    }
    return {};
}

}  // namespace strata

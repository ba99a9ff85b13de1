#include "protocol/transform_parser.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "protocol/edit_schema.h"

namespace strata::protocol {

namespace {

/// Quaternions are normalised, but only lengths within these bounds are taken for a rotation.
constexpr double MIN_QUATERNION_LENGTH = 1e-6;
constexpr double MAX_QUATERNION_LENGTH = 1e6;

std::string short_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

Affine parse_matrix(FieldReader& r, const Json& v, const std::string& ptr) {
    const std::vector<float> m = r.floats(v, ptr);
    if (m.size() != 12 && m.size() != 16)
        r.schema_error(ptr, "a transform array has 12 or 16 numbers (row-major), not " +
                                std::to_string(m.size()));
    Affine a;
    std::copy_n(m.begin(), 12, a.m.begin());
    if (m.size() == 16) {
        static constexpr float LAST_ROW[4] = {0.0f, 0.0f, 0.0f, 1.0f};
        for (std::size_t k = 0; k < 4; ++k) {
            if (m[12 + k] != LAST_ROW[k])
                r.record_value_error(
                    child(ptr, 12 + k),
                    "the last row of a 4x4 transform must be 0 0 0 1 (affine only)");
        }
    }
    return a;
}

Affine parse_trs(FieldReader& r, const Json& v, const std::string& ptr) {
    static const MemberRule TRS = schema_members("/$defs/transform/oneOf/2");
    r.expect_object(v, ptr, TRS);
    const Json* rotate = FieldReader::member(v, "rotate_deg");
    const Json* quaternion = FieldReader::member(v, "quaternion");
    if (rotate && quaternion)
        r.schema_error(child(ptr, "quaternion"), "give rotate_deg or quaternion, not both");

    Vec3 translate(0.0f);
    if (const Json* t = FieldReader::member(v, "translate"))
        translate = r.vec3(*t, child(ptr, "translate"));
    Affine rotation;
    if (rotate) rotation = Affine::rotation_euler_deg(r.vec3(*rotate, child(ptr, "rotate_deg")));
    if (quaternion) {
        const Vec4 q = r.vec4(*quaternion, child(ptr, "quaternion"));
        // In double: a float squared length overflows at ~1.8e19, and an overflowed length
        // would normalise to the identity. A rotation is a unit quaternion; lengths far from 1
        // are a client bug.
        const glm::dvec4 qd(q);
        const double len = std::sqrt(glm::dot(qd, qd));
        if (!(len > 0.0))
            r.record_value_error(child(ptr, "quaternion"), "quaternion has zero length");
        else if (len < MIN_QUATERNION_LENGTH || len > MAX_QUATERNION_LENGTH)
            r.record_value_error(
                child(ptr, "quaternion"),
                "quaternion length " + short_number(len) +
                    " is outside [1e-6, 1e6]; send a unit quaternion (x, y, z, w)");
        rotation = Affine::rotation_quaternion(q);
    }
    Vec3 scale(1.0f);
    if (const Json* s = FieldReader::member(v, "scale")) {
        const std::string sp = child(ptr, "scale");
        scale = s->is_number() ? Vec3(r.number(*s, sp)) : r.vec3(*s, sp);
    }
    return Affine::trs(translate, rotation, scale);
}

}  // namespace

Affine parse_transform(FieldReader& r, const Json& v, const std::string& ptr) {
    if (v.is_object()) return parse_trs(r, v, ptr);
    if (v.is_array() || is_packed_numbers(v)) return parse_matrix(r, v, ptr);
    r.schema_error(ptr,
                   "expected a transform: an array of 12 or 16 numbers or an object with "
                   "translate, rotate_deg or quaternion, and scale");
}

}  // namespace strata::protocol

#pragma once
// Small math vocabulary on top of GLM: finite checks, bounds and the 3x4 affine transform that
// instances carry (row-major, the layout Embree's RTC_FORMAT_FLOAT3X4_ROW_MAJOR expects).

#include <array>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace strata {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;

inline bool is_finite(float v) { return std::isfinite(v); }
inline bool is_finite(const Vec3& v) { return is_finite(v.x) && is_finite(v.y) && is_finite(v.z); }
inline bool is_finite(const Vec2& v) { return is_finite(v.x) && is_finite(v.y); }
inline bool is_finite(const Vec4& v) { return is_finite(Vec3(v)) && is_finite(v.w); }

/// Rec. 709 luminance of linear RGB.
inline float luminance(const Vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/// Axis-aligned box; empty when lower > upper.
struct Bounds3 {
    Vec3 lower{std::numeric_limits<float>::infinity()};
    Vec3 upper{-std::numeric_limits<float>::infinity()};

    bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
    void extend(const Vec3& p) {
        lower = glm::min(lower, p);
        upper = glm::max(upper, p);
    }
    void extend(const Bounds3& b) {
        lower = glm::min(lower, b.lower);
        upper = glm::max(upper, b.upper);
    }
    Vec3 extent() const { return empty() ? Vec3(0.0f) : upper - lower; }
    Vec3 center() const { return 0.5f * (lower + upper); }
    /// Surface area (0 for an empty box); the quantity SAH cost and the refit policy use.
    float surface_area() const {
        const Vec3 e = extent();
        return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
};

/// Row-major 3x4 affine transform: rows are (r00 r01 r02 tx), (r10 r11 r12 ty), (r20 r21 r22 tz).
/// Most motion keys (transforms over time) one instance may have: Embree's
/// RTC_MAX_TIME_STEP_COUNT.
constexpr std::size_t MAX_MOTION_KEYS = 129;

struct Affine {
    std::array<float, 12> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

    static Affine identity() { return {}; }
    static Affine translation(const Vec3& t);
    static Affine scaling(const Vec3& s);
    /// Rotation from Euler angles in degrees, applied X first, then Y, then Z (R = Rz*Ry*Rx).
    static Affine rotation_euler_deg(const Vec3& deg);
    /// Rotation from a quaternion (x, y, z, w); it is normalised first.
    static Affine rotation_quaternion(const Vec4& xyzw);
    /// translate * rotate * scale.
    static Affine trs(const Vec3& t, const Affine& r, const Vec3& s);

    float at(int row, int col) const { return m[row * 4 + col]; }
    float& at(int row, int col) { return m[row * 4 + col]; }

    Vec3 transform_point(const Vec3& p) const;
    Vec3 transform_vector(const Vec3& v) const;
    /// Determinant of the linear 3x3 part.
    float determinant() const;
    /// Inverse; only meaningful for a non-singular transform.
    Affine inverse() const;
    /// this * other.
    Affine operator*(const Affine& other) const;
    /// Inverse-transpose of the linear part, for transforming normals.
    glm::mat3 normal_matrix() const;
    bool is_finite() const;
    /// The box around the transformed corners of `b`.
    Bounds3 transform_bounds(const Bounds3& b) const;
    /// The linear blend (1 - t) * a + t * b of every number: how Embree interpolates an
    /// instance's transform keys.
    static Affine lerp(const Affine& a, const Affine& b, float t);
    /// The 16 numbers of the 4x4 row-major matrix (last row 0 0 0 1).
    std::array<float, 16> to_rows16() const;

    friend bool operator==(const Affine&, const Affine&) = default;
};

/// Largest coordinate a camera position or a translation may have. Embree refuses rays whose
/// components exceed about 1.8e18 (its FLT_LARGE; a debug-enabled Embree asserts), and a float
/// at 1e15 already has a spacing of 0.125: nothing useful lies beyond.
constexpr double MAX_COORDINATE = 1e15;

/// Limits on instance transforms: float precision in object space suffers beyond these.
constexpr double MIN_AXIS_SCALE = 1e-6;
constexpr double MAX_AXIS_SCALE = 1e6;
constexpr double MAX_ANISOTROPY_INV = 1e-6;  ///< shortest axis / longest axis must exceed this

/// Why a transform cannot be used, or nullptr when it can: non-finite values, a translation
/// beyond MAX_COORDINATE, an axis scaled outside [1e-6, 1e6], axis scales differing by more than
/// 1e6, nearly coplanar axes, or an inverse that does not come out finite.
const char* transform_problem(const Affine& t);

}  // namespace strata

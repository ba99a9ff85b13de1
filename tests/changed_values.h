#pragma once
// For field-table tests: a value of each field type other than the one given, so a test can
// change every field of a kind without naming any (limits are not this helper's business).

#include <string>
#include <type_traits>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata::test {

inline float changed(float v) {
    return v >= 1e6f ? v * 0.5f : v + 0.5f;  // past 1e6, +0.5 may round back to v
}
inline Vec3 changed(const Vec3& v) {
    return v + Vec3(0.25f);
}
inline bool changed(bool v) {
    return !v;
}
inline uint32_t changed(uint32_t v) {
    return v + 7;
}
inline Affine changed(const Affine& v) {
    return Affine::translation({1, 2, 3}) * v;
}
/// Motion keys: two when there were none, none when there were some.
inline std::vector<Affine> changed(const std::vector<Affine>& v) {
    if (!v.empty()) return {};
    return {Affine::identity(), Affine::translation({1, 2, 3})};
}
/// Keyframes: two when there were none, none when there were some.
inline std::vector<Keyframe> changed(const std::vector<Keyframe>& v) {
    if (!v.empty()) return {};
    return {{0.0f, Affine::identity()}, {1.5f, Affine::translation({1, 2, 3})}};
}
inline std::string changed(const std::string& v) {
    return v + "x";
}
/// The next value of a three-valued enum.
template <class E>
requires std::is_enum_v<E>
E changed(E v) {
    return static_cast<E>((static_cast<int>(v) + 1) % 3);
}

}  // namespace strata::test

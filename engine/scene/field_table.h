#pragma once
// An object kind's plain fields, each declared once: a row names the field on the wire, says what
// it means, bounds it, and points at where it lives in the kind's record (what the scene holds),
// in its add edit and, as an optional, in its update edit, with the dirty bit a change sets. The
// rules, the undo log, the journal and snapshot codec, the wire parser, the JSON writer and the
// schema and docs generators all walk these tables (object_fields.h holds them), so a new field is
// a row plus its members.
//
// A kind is a struct naming its Record, Add and Update types (NoUpdate when it has no update op)
// and its Dirty enum, with `static constexpr auto table()` returning a tuple of Field rows.
//
// Not in the tables: fields that name other objects (resolved by the rules against the scene)
// and nested objects (a material's sampler, a mesh's build options, a mesh's arrays), which have
// rules of their own next to their op.

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "engine/core/boxed.h"
#include "engine/core/check.h"
#include "engine/core/math.h"
#include "engine/core/result.h"
#include "engine/scene/dirty.h"
#include "engine/scene/types.h"

namespace strata {

/// Bounds of a number, of each component of a vector, or of a text's length in bytes.
struct Limits {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    bool lo_open = false;
    bool hi_open = false;

    constexpr bool has_lo() const { return lo > -std::numeric_limits<double>::infinity(); }
    constexpr bool has_hi() const { return hi < std::numeric_limits<double>::infinity(); }
    /// False for NaN.
    constexpr bool contains(double v) const {
        return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    }
};

/// [lo, hi]
constexpr Limits closed(double lo, double hi) {
    return {lo, hi, false, false};
}
/// >= lo
constexpr Limits at_least(double lo) {
    return {lo, std::numeric_limits<double>::infinity(), false, false};
}
/// (lo, hi]
constexpr Limits above_up_to(double lo, double hi) {
    return {lo, hi, true, false};
}
/// (lo, hi)
constexpr Limits open(double lo, double hi) {
    return {lo, hi, true, true};
}

/// A number as people write it: 90, 0.5, 1e12.
std::string number_text(double v);
/// The limits as the docs and messages write them: "[0, 1]", "(0, 90]", ">= 0".
std::string limits_text(const Limits& l);
/// As a message says it: "in [0, 1]", ">= 0".
std::string limits_phrase(const Limits& l);

/// The longest display name, in bytes.
constexpr std::size_t MAX_NAME_BYTES = 1024;

/// What a row says about its field, besides its C++ type and place.
struct FieldInfo {
    std::string_view name;  ///< the member on the wire, in JSON and in error fields
    std::string_view doc;   ///< one line for the schema and the docs
    /// Numbers: the value; vectors: each component; text: the length in bytes.
    Limits limits = {};
    /// Enums: the wire name of each value, in the order of the enum.
    std::span<const std::string_view> choices = {};
    /// 0: part of the kind's first journal layout, in table order; n > 0: a field added later,
    /// written in the edit's tagged section under number n (edit_codec.cpp).
    uint8_t tag = 0;
    /// Identifies the object to a person or a client (a name, a user id): picks report it too.
    bool label = false;
};

/// The update edit of a kind that has none.
struct NoUpdate {};

/// Where a row's value lives in a record: a member (`T Record::*`), or a member of the box of
/// rarely set fields a record holds (`InBox`), allocated by the first value other than the
/// default.
template <class Record, class Box, class T>
struct InBox {
    Boxed<Box> Record::*box;
    T Box::*member;
};

template <class R, class T>
const T& record_value(const R& r, T R::*member) {
    return r.*member;
}
template <class R, class Box, class T>
const T& record_value(const R& r, InBox<R, Box, T> at) {
    return (*(r.*(at.box))).*(at.member);
}
template <class R, class T, class V>
void set_record_value(R& r, T R::*member, V&& v) {
    r.*member = std::forward<V>(v);
}
template <class R, class Box, class T, class V>
void set_record_value(R& r, InBox<R, Box, T> at, V&& v) {
    Boxed<Box>& box = r.*(at.box);
    if (!box && v == Boxed<Box>::defaults().*(at.member)) return;
    box.mut().*(at.member) = std::forward<V>(v);
}

/// One row. `K` is the kind, `T` the field's value type, `At` where records hold it.
template <class K, class T, class At = T K::Record::*>
struct Field {
    using Kind = K;
    using Type = T;
    FieldInfo info;
    At record;
    T K::Add::*add;
    std::optional<T> K::Update::*update;  ///< null when the kind has no update op
    typename K::Dirty dirty;              ///< what an update of it marks; 0: nothing
};

/// A row of kind `K`; T is deduced from the member pointers.
template <class K, class T>
constexpr Field<K, T> field(FieldInfo info, T K::Record::*record, T K::Add::*add,
                            std::type_identity_t<std::optional<T> K::Update::*> update,
                            typename K::Dirty dirty) {
    return {info, record, add, update, dirty};
}
/// A row of kind `K` whose records keep it in their box of rarely set fields.
template <class K, class Box, class T>
constexpr Field<K, T, InBox<typename K::Record, Box, T>> field(
    FieldInfo info, InBox<typename K::Record, Box, T> record, T K::Add::*add,
    std::type_identity_t<std::optional<T> K::Update::*> update, typename K::Dirty dirty) {
    return {info, record, add, update, dirty};
}

/// The three places of member `m` in a kind whose record, add and update edits all name it `m`.
#define STRATA_FIELD_OF(K, m) &K::Record::m, &K::Add::m, &K::Update::m
/// The same for a member `m` that records keep in their box `box` of type `Box`.
#define STRATA_BOXED_FIELD_OF(K, Box, box, m) \
    InBox<K::Record, Box, decltype(Box::m)>{&K::Record::box, &Box::m}, &K::Add::m, &K::Update::m

/// Kind `K`'s table, built once.
template <class K>
inline constexpr auto FIELDS = K::table();

/// Calls `fn(row)` for every row of kind `K`, in table order.
template <class K, class Fn>
constexpr void for_each_field(Fn&& fn) {
    std::apply([&](const auto&... row) { (fn(row), ...); }, FIELDS<K>);
}

/// The field of `row` in `v`, which is the kind's Record or its Add.
template <class Row, class V>
constexpr auto& field_in(const Row& row, V& v) {
    using K = typename Row::Kind;
    if constexpr (!std::is_same_v<std::remove_const_t<V>, typename K::Record>)
        return v.*(row.add);
    else if constexpr (std::is_member_object_pointer_v<decltype(row.record)>)
        return v.*(row.record);
    else
        return record_value(v, row.record);  // read-only: boxed rows are written by value
}

/// The row of kind `K` named `name` (a name no row has is a bug in Strata: checked).
template <class K>
const FieldInfo& field_info(std::string_view name) {
    const FieldInfo* found = nullptr;
    for_each_field<K>([&](const auto& row) {
        if (row.info.name == name) found = &row.info;
    });
    STRATA_CHECK(found != nullptr);
    return *found;
}

/// The values of every field of a record: what the undo log keeps before an update.
template <class Rows>
struct ValuesOf;
template <class... Rows>
struct ValuesOf<std::tuple<Rows...>> {
    using type = std::tuple<typename Rows::Type...>;
};
template <class K>
using FieldValues = typename ValuesOf<std::remove_const_t<decltype(FIELDS<K>)>>::type;

template <class K>
FieldValues<K> save_fields(const typename K::Record& r) {
    return std::apply(
        [&](const auto&... row) { return FieldValues<K>{record_value(r, row.record)...}; },
        FIELDS<K>);
}

template <class K>
void restore_fields(typename K::Record& r, FieldValues<K>&& saved) {
    std::apply(
        [&](const auto&... row) {
            std::apply(
                [&](auto&... value) { (set_record_value(r, row.record, std::move(value)), ...); },
                saved);
        },
        FIELDS<K>);
}

/// An update that sets every field back to saved values (the inverse of an update: undo history).
template <class K>
typename K::Update update_from(FieldValues<K>&& saved) {
    typename K::Update u{};
    std::apply(
        [&](const auto&... row) {
            std::apply([&](auto&... value) { ((u.*(row.update) = std::move(value)), ...); }, saved);
        },
        FIELDS<K>);
    return u;
}

/// Copies every field of an add edit into a new record.
template <class K>
void copy_added(typename K::Record& r, typename K::Add& a) {
    for_each_field<K>(
        [&](const auto& row) { set_record_value(r, row.record, std::move(a.*(row.add))); });
}

/// The fields of a record as an add edit has them (for the batch that rebuilds a scene).
template <class K>
void copy_to_add(typename K::Add& a, const typename K::Record& r) {
    for_each_field<K>([&](const auto& row) { a.*(row.add) = record_value(r, row.record); });
}

/// Copies the fields an update sets onto a record; returns the dirty bits of what it set.
template <class K>
DirtyBits<typename K::Dirty> apply_update(typename K::Record& r, const typename K::Update& u) {
    DirtyBits<typename K::Dirty> bits;
    for_each_field<K>([&](const auto& row) {
        if (!row.update) return;
        if (const auto& set = u.*(row.update)) {
            set_record_value(r, row.record, *set);
            bits |= row.dirty;
        }
    });
    return bits;
}

/// An update that sets every field to the record's value (for the batch that rebuilds a scene).
template <class K>
typename K::Update update_to(const typename K::Record& r) {
    typename K::Update u{};
    for_each_field<K>([&](const auto& row) {
        if (row.update) u.*(row.update) = record_value(r, row.record);
    });
    return u;
}

// Step: value checks -------------------------------------------------------------------------

/// Checks one value against its row: numbers and vector components finite and within the
/// limits, text well-formed and short enough, transforms invertible. The error names the field.
Status refuse_number(const FieldInfo& info, float v);
Status refuse_vector(const FieldInfo& info, const Vec3& v);
inline Status check_value(const FieldInfo& info, float v) {
    if (std::isfinite(v) && info.limits.contains(v)) return {};
    return refuse_number(info, v);
}
inline Status check_value(const FieldInfo& info, const Vec3& v) {
    if (is_finite(v) && info.limits.contains(v.x) && info.limits.contains(v.y) &&
        info.limits.contains(v.z))
        return {};
    return refuse_vector(info, v);
}
Status check_text(const FieldInfo& info, const std::string& v);
/// Text: the empty text (no name) is the common case, checked inline.
inline Status check_value(const FieldInfo& info, const std::string& v) {
    if (v.empty()) return {};
    return check_text(info, v);
}
Status check_value(const FieldInfo& info, const Affine& v);
/// Motion keys: none, or 2 to MAX_MOTION_KEYS transforms that each keep the transform rule.
Status check_value(const FieldInfo& info, const std::vector<Affine>& keys);
/// Keyframes: at most MAX_ANIMATION_KEYS, times finite within MAX_SCENE_TIME and increasing,
/// transforms that keep the transform rule.
Status check_value(const FieldInfo& info, const std::vector<Keyframe>& keys);
inline Status check_value(const FieldInfo&, bool) {
    return {};
}
inline Status check_value(const FieldInfo& info, uint32_t v) {
    if (info.limits.contains(double(v))) return {};
    return refuse_number(info, float(v));
}
template <class E>
requires std::is_enum_v<E>
Status check_value(const FieldInfo& info, E v) {
    if (static_cast<std::size_t>(v) < info.choices.size()) return {};
    return failure(ErrorCode::InvalidArgument,
                   std::string(info.name) + " is not one of its " +
                       std::to_string(info.choices.size()) + " values",
                   std::string(info.name));
}

/// Whether a value keeps its row's rule: the accepted case, with no Status built (this runs for
/// every field of every edit). check_value() says why when it does not.
inline bool value_ok(const FieldInfo& info, float v) {
    return std::isfinite(v) && info.limits.contains(v);
}
inline bool value_ok(const FieldInfo& info, const Vec3& v) {
    return is_finite(v) && info.limits.contains(v.x) && info.limits.contains(v.y) &&
           info.limits.contains(v.z);
}
inline bool value_ok(const FieldInfo& info, const std::string& v) {
    return v.empty() || check_text(info, v).has_value();
}
inline bool value_ok(const FieldInfo&, const Affine& v) {
    return transform_problem(v) == nullptr;
}
bool value_ok(const FieldInfo& info, const std::vector<Affine>& keys);
inline bool value_ok(const FieldInfo& info, const std::vector<Keyframe>& keys) {
    return keys.empty() || check_value(info, keys).has_value();
}
inline bool value_ok(const FieldInfo&, bool) {
    return true;
}
inline bool value_ok(const FieldInfo& info, uint32_t v) {
    return info.limits.contains(double(v));
}
template <class E>
requires std::is_enum_v<E>
bool value_ok(const FieldInfo& info, E v) {
    return static_cast<std::size_t>(v) < info.choices.size();
}

/// Checks every field of `v` (the kind's Record or Add); the first refusal comes back.
template <class K, class V>
Status check_fields(const V& v) {
    Status result;
    std::apply(
        [&](const auto&... row) {
            (void)((value_ok(row.info, field_in(row, v)) ||
                    (result = check_value(row.info, field_in(row, v)), false)) &&
                   ...);
        },
        FIELDS<K>);
    return result;
}

/// Checks the fields an update sets.
template <class K>
Status check_update(const typename K::Update& u) {
    Status result;
    const auto ok = [&](const auto& row) {
        if constexpr (std::is_same_v<typename K::Update, NoUpdate>) {
            return true;
        } else {
            const auto& set = u.*(row.update);
            if (!set || value_ok(row.info, *set)) return true;
            result = check_value(row.info, *set);
            return false;
        }
    };
    std::apply([&](const auto&... row) { (void)(ok(row) && ...); }, FIELDS<K>);
    return result;
}

}  // namespace strata

#pragma once
// The object kinds' field tables (engine/scene/object_fields.h) on the wire: op parsers read the
// fields through them, the scene's JSON documents write them, and the edit-batch schema and the
// README's field tables are generated from them.

#include <optional>
#include <string>
#include <type_traits>

#include "engine/scene/object_fields.h"
#include "protocol/edit_ops.h"
#include "protocol/edit_schema.h"

namespace strata::protocol {

namespace detail {

template <class T>
bool read_field(OpFields& f, const FieldInfo& info, T& out) {
    if constexpr (std::is_enum_v<T>)
        return f.read(info.name, out, info.choices);
    else if constexpr (std::is_same_v<T, std::string>)
        return f.read_text(info.name, out);
    else
        return f.read(info.name, out);
}
template <class T>
bool read_field(OpFields& f, const FieldInfo& info, std::optional<T>& out) {
    T value{};
    if (!read_field(f, info, value)) return false;
    out = std::move(value);
    return true;
}

Json field_json(const FieldInfo& info, float v);
Json field_json(const FieldInfo& info, const Vec3& v);
Json field_json(const FieldInfo& info, bool v);
Json field_json(const FieldInfo& info, uint32_t v);
Json field_json(const FieldInfo& info, const Affine& v);
Json field_json(const FieldInfo& info, const std::vector<Affine>& v);
Json field_json(const FieldInfo& info, const std::vector<Keyframe>& v);
Json field_json(const FieldInfo& info, const std::string& v);
Json choice_json(const FieldInfo& info, std::size_t v);
template <class E>
requires std::is_enum_v<E>
Json field_json(const FieldInfo& info, E v) {
    return choice_json(info, static_cast<std::size_t>(v));
}

/// A field's schema: its type (with limits) and description, and its default when given.
OrderedJson field_schema(const FieldInfo& info, const float* fallback);
OrderedJson field_schema(const FieldInfo& info, const Vec3* fallback);
OrderedJson field_schema(const FieldInfo& info, const bool* fallback);
OrderedJson field_schema(const FieldInfo& info, const uint32_t* fallback);
OrderedJson field_schema(const FieldInfo& info, const Affine* fallback);
OrderedJson field_schema(const FieldInfo& info, const std::vector<Affine>* fallback);
OrderedJson field_schema(const FieldInfo& info, const std::vector<Keyframe>* fallback);
OrderedJson field_schema(const FieldInfo& info, const std::string* fallback);
OrderedJson choice_schema(const FieldInfo& info, const std::size_t* fallback);
template <class E>
requires std::is_enum_v<E>
OrderedJson field_schema(const FieldInfo& info, const E* fallback) {
    const std::size_t v = fallback ? static_cast<std::size_t>(*fallback) : 0;
    return choice_schema(info, fallback ? &v : nullptr);
}

/// A field's row in the README: | name | type | default | range | cost | doc |.
std::string field_row(const FieldInfo& info, const OrderedJson& schema, std::string_view cost);

}  // namespace detail

/// Reads the fields of kind `K` an op object has into its add value.
template <class K>
void read_added(OpFields& f, typename K::Add& v) {
    for_each_field<K>([&](const auto& row) { detail::read_field(f, row.info, v.*(row.add)); });
}

/// Reads the fields of kind `K` an op object has into its update edit (absent: unset).
template <class K>
void read_updates(OpFields& f, typename K::Update& u) {
    for_each_field<K>([&](const auto& row) { detail::read_field(f, row.info, u.*(row.update)); });
}

/// Adds every field of record `r` to the JSON object `j`.
template <class K>
void write_fields(Json& j, const typename K::Record& r) {
    for_each_field<K>([&](const auto& row) {
        j[std::string(row.info.name)] = detail::field_json(row.info, record_value(r, row.record));
    });
}

/// Adds the label fields (FieldInfo::label) among saved values `values` to the JSON object `j`.
template <class K>
void write_labels(Json& j, const FieldValues<K>& values) {
    std::apply(
        [&](const auto&... row) {
            std::apply(
                [&](const auto&... v) {
                    ((row.info.label
                          ? void(j[std::string(row.info.name)] = detail::field_json(row.info, v))
                          : void()),
                     ...);
                },
                values);
        },
        FIELDS<K>);
}

/// The schema `properties` of kind `K`'s fields, with their defaults in an add op (`Added`),
/// without in an update op (where absent means unchanged).
template <class K, bool Added>
OrderedJson field_properties() {
    OrderedJson properties = OrderedJson::object();
    const typename K::Add defaults{};
    for_each_field<K>([&](const auto& row) {
        properties[std::string(row.info.name)] =
            detail::field_schema(row.info, Added ? &(defaults.*(row.add)) : nullptr);
    });
    return properties;
}

/// Kind `K`'s fields as a Markdown table for protocol/README.md.
template <class K>
std::string fields_markdown() {
    std::string out =
        "| field | type | default | range | a change costs | meaning "
        "|\n|---|---|---|---|---|---|\n";
    const typename K::Add defaults{};
    for_each_field<K>([&](const auto& row) {
        out += detail::field_row(row.info, detail::field_schema(row.info, &(defaults.*(row.add))),
                                 commit_cost(row.dirty));
    });
    return out;
}

/// A material's texture slots (TEXTURE_SLOTS) as a Markdown table for protocol/README.md.
inline std::string texture_slots_markdown() {
    std::string out = "| member | texture's color_space | meaning |\n|---|---|---|\n";
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS)
        out += "| `" + std::string(slot.field) + "` | `" +
               (slot.space == TextureColorSpace::Srgb ? "srgb" : "linear") + "` | " +
               std::string(slot.doc) + " |\n";
    return out;
}

}  // namespace strata::protocol

#include "protocol/field_json.h"

#include "protocol/scene_json.h"

namespace strata::protocol::detail {

namespace {

/// `schema` with the description, then the default when there is one.
OrderedJson described(OrderedJson schema, const FieldInfo& info, const OrderedJson* fallback) {
    schema["description"] = info.doc;
    if (fallback) schema["default"] = *fallback;
    return schema;
}

/// JSON Schema's keywords for the limits of a number.
void add_limits(OrderedJson& schema, const Limits& l) {
    if (l.has_lo()) schema[l.lo_open ? "exclusiveMinimum" : "minimum"] = l.lo;
    if (l.has_hi()) schema[l.hi_open ? "exclusiveMaximum" : "maximum"] = l.hi;
}

OrderedJson ordered(const Json& j) {
    return OrderedJson::parse(j.dump());
}

/// A default as the docs write it: `[0, 3, 0]`, `0.5`, `"point"`.
std::string docs_value(const OrderedJson& v) {
    if (v.is_array()) {
        std::string out = "[";
        for (const auto& e : v) out += (out.size() > 1 ? ", " : "") + docs_value(e);
        return out + "]";
    }
    if (v.is_number_float() && v.get<double>() == double(int64_t(v.get<double>())))
        return std::to_string(int64_t(v.get<double>()));
    return v.dump();
}

}  // namespace

Json field_json(const FieldInfo&, float v) {
    return float_to_json(v);
}
Json field_json(const FieldInfo&, const Vec3& v) {
    return vec3_to_json(v);
}
Json field_json(const FieldInfo&, bool v) {
    return v;
}
Json field_json(const FieldInfo&, uint32_t v) {
    return v;
}
Json field_json(const FieldInfo&, const Affine& v) {
    return affine_to_json(v);
}
Json field_json(const FieldInfo&, const std::vector<Affine>& v) {
    Json out = Json::array();
    for (const Affine& k : v) out.push_back(affine_to_json(k));
    return out;
}
Json field_json(const FieldInfo&, const std::vector<Keyframe>& v) {
    Json out = Json::array();
    for (const Keyframe& k : v)
        out.push_back({{"time", float_to_json(k.time)}, {"transform", affine_to_json(k.transform)}});
    return out;
}
Json field_json(const FieldInfo&, const std::string& v) {
    return v;
}
Json choice_json(const FieldInfo& info, std::size_t v) {
    return v < info.choices.size() ? Json(info.choices[v]) : Json(nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const float* fallback) {
    OrderedJson s = {{"type", "number"}};
    add_limits(s, info.limits);
    const OrderedJson d = fallback ? ordered(float_to_json(*fallback)) : OrderedJson();
    return described(std::move(s), info, fallback ? &d : nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const Vec3* fallback) {
    OrderedJson s = {{"$ref", "#/$defs/vec3"}};
    if (info.limits.has_lo() || info.limits.has_hi()) {
        OrderedJson items = {{"type", "number"}};
        add_limits(items, info.limits);
        s["items"] = std::move(items);
    }
    const OrderedJson d = fallback ? ordered(vec3_to_json(*fallback)) : OrderedJson();
    return described(std::move(s), info, fallback ? &d : nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const bool* fallback) {
    const OrderedJson d = fallback ? OrderedJson(*fallback) : OrderedJson();
    return described({{"type", "boolean"}}, info, fallback ? &d : nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const uint32_t* fallback) {
    const OrderedJson d = fallback ? OrderedJson(*fallback) : OrderedJson();
    OrderedJson s = {{"$ref", "#/$defs/u32"}};
    add_limits(s, info.limits);
    return described(std::move(s), info, fallback ? &d : nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const Affine*) {
    // The default is the identity, which the description says rather than a 16-number array.
    return described({{"$ref", "#/$defs/transform"}}, info, nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const std::vector<Affine>*) {
    // The default is no keys, which the description says.
    return described({{"type", "array"},
                      {"items", {{"$ref", "#/$defs/transform"}}},
                      {"maxItems", MAX_MOTION_KEYS}},
                     info, nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const std::vector<Keyframe>*) {
    // The default is no keyframes, which the description says.
    return described({{"type", "array"},
                      {"items", {{"$ref", "#/$defs/keyframe"}}},
                      {"maxItems", MAX_ANIMATION_KEYS}},
                     info, nullptr);
}

OrderedJson field_schema(const FieldInfo& info, const std::string* fallback) {
    const OrderedJson d = fallback ? OrderedJson(*fallback) : OrderedJson();
    return described({{"$ref", "#/$defs/text"}}, info, fallback ? &d : nullptr);
}

OrderedJson choice_schema(const FieldInfo& info, const std::size_t* fallback) {
    OrderedJson names = OrderedJson::array();
    for (std::string_view c : info.choices) names.push_back(c);
    const OrderedJson d = fallback ? OrderedJson(info.choices[*fallback]) : OrderedJson();
    return described({{"enum", std::move(names)}}, info, fallback ? &d : nullptr);
}

std::string field_row(const FieldInfo& info, const OrderedJson& schema, std::string_view cost) {
    std::string type, range;
    const std::string ref = schema.value("$ref", "");
    if (schema.contains("enum")) {
        for (const auto& c : schema["enum"]) type += (type.empty() ? "" : " \\| ") + c.dump();
    } else if (ref.ends_with("/vec3")) {
        type = "[x, y, z]";
    } else if (ref.ends_with("/u32")) {
        type = "integer";
        range = "[0, 4294967295]";
    } else if (ref.ends_with("/transform")) {
        type = "transform";
    } else if (ref.ends_with("/text")) {
        type = "string";
        range = "at most " + std::to_string(MAX_NAME_BYTES) + " bytes";
    } else if (schema.value("type", "") == "array" &&
               schema["items"].value("$ref", "").ends_with("/keyframe")) {
        type = "array of keyframes";
        range = "at most " + std::to_string(MAX_ANIMATION_KEYS) + " keys, times increasing";
    } else if (schema.value("type", "") == "array") {
        type = "array of transforms";
        range = "none, or 2 to " + std::to_string(MAX_MOTION_KEYS) + " keys";
    } else {
        type = schema.value("type", "");
    }
    if (info.limits.has_lo() || info.limits.has_hi()) range = limits_text(info.limits);
    const std::string fallback = schema.contains("default")
                                     ? "`" + docs_value(schema["default"]) + "`"
                                 : type == "transform"           ? "identity"
                                 : type.starts_with("array of") ? "`[]`"
                                                                : "";
    return "| `" + std::string(info.name) + "` | " + type + " | " + fallback + " | " + range +
           " | " + std::string(cost) + " | " + std::string(info.doc) + " |\n";
}

}  // namespace strata::protocol::detail

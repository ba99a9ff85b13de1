#include "protocol/json_fields.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "engine/core/utf8.h"
#include "protocol/base64.h"

namespace strata::protocol {

namespace {

const char* type_name(const Json& v) {
    if (is_packed_numbers(v)) return "array";
    switch (v.type()) {
        case Json::value_t::null:
            return "null";
        case Json::value_t::boolean:
            return "boolean";
        case Json::value_t::string:
            return "string";
        case Json::value_t::array:
            return "array";
        case Json::value_t::object:
            return "object";
        case Json::value_t::number_integer:
        case Json::value_t::number_unsigned:
        case Json::value_t::number_float:
            return "number";
        default:
            return "value";
    }
}

bool fits_float(double d) {
    return std::isfinite(d) && std::abs(d) <= double(std::numeric_limits<float>::max());
}

template <class T>
T load_le(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    if constexpr (std::endian::native == std::endian::big) {
        auto* b = reinterpret_cast<unsigned char*>(&v);
        for (std::size_t i = 0; i < sizeof v / 2; ++i) std::swap(b[i], b[sizeof v - 1 - i]);
    }
    return v;
}

}  // namespace

std::string child(const std::string& ptr, std::string_view key) {
    return ptr + "/" + escape_pointer_token(key);
}

std::string child(const std::string& ptr, std::size_t index) {
    return ptr + "/" + std::to_string(index);
}

void FieldReader::record_value_error(std::string pointer, std::string message, ErrorCode code) {
    if (m_value_error) return;
    m_value_error = problem_at(problem_type_of(code), std::move(pointer), message, m_edit_index);
}

void FieldReader::schema_error(const std::string& ptr, std::string message) const {
    throw RequestFailure(problem_at(ProblemType::InvalidRequest, ptr, message, m_edit_index));
}

bool MemberRule::allows(std::string_view key) const {
    for (const std::string& a : allowed) {
        if (a == key) return true;
    }
    return false;
}

template <class Names>
void FieldReader::expect_known_members(const Json& v, const std::string& ptr,
                                       const Names& allowed) const {
    if (!v.is_object()) schema_error(ptr, std::string("expected an object, got ") + type_name(v));
    for (const auto& [key, value] : v.items()) {
        bool known = false;
        for (std::string_view a : allowed) known |= a == key;
        if (!known) {
            std::string list;
            for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            schema_error(child(ptr, key), "unknown member '" + key + "' (allowed: " + list + ")");
        }
    }
}

void FieldReader::expect_object(const Json& v, const std::string& ptr,
                                std::initializer_list<std::string_view> allowed) const {
    expect_known_members(v, ptr, allowed);
}

void FieldReader::expect_object(const Json& v, const std::string& ptr,
                                const MemberRule& rule) const {
    expect_known_members(v, ptr, rule.allowed);
    for (const std::string& key : rule.required) required(v, ptr, key);
}

const Json* FieldReader::member(const Json& obj, std::string_view key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

const Json& FieldReader::required(const Json& obj, const std::string& ptr,
                                  std::string_view key) const {
    if (const Json* m = member(obj, key)) return *m;
    schema_error(child(ptr, key), "missing required member '" + std::string(key) + "'");
}

std::string FieldReader::id(const Json& v, const std::string& ptr) const {
    if (!v.is_string())
        schema_error(ptr, std::string("expected an id string, got ") + type_name(v));
    const auto& s = v.get_ref<const std::string&>();
    if (const char* why = id_problem(s)) schema_error(ptr, std::string("id ") + why);
    return s;
}

bool FieldReader::reserve_shape_triangles(uint64_t triangles, const std::string& ptr) {
    m_shape_triangles += triangles;
    if (m_shape_triangles <= MAX_SHAPE_TRIANGLES_PER_BATCH) return true;
    record_value_error(ptr,
                       "the batch's shapes would generate " + std::to_string(m_shape_triangles) +
                           " triangles; at most " + std::to_string(MAX_SHAPE_TRIANGLES_PER_BATCH) +
                           " per batch",
                       ErrorCode::TooLarge);
    return false;
}

std::string FieldReader::text(const Json& v, const std::string& ptr) const {
    if (!v.is_string()) schema_error(ptr, std::string("expected a string, got ") + type_name(v));
    return v.get<std::string>();
}

std::size_t FieldReader::choice(const Json& v, const std::string& ptr,
                                std::initializer_list<std::string_view> choices) const {
    return choice(v, ptr, std::span<const std::string_view>(choices.begin(), choices.size()));
}

std::size_t FieldReader::choice(const Json& v, const std::string& ptr,
                                std::span<const std::string_view> choices) const {
    std::string list;
    std::size_t i = 0;
    for (std::string_view c : choices) {
        if (v.is_string() && v.get_ref<const std::string&>() == c) return i;
        list += (i++ ? ", " : "") + ("\"" + std::string(c) + "\"");
    }
    schema_error(ptr, "expected one of " + list + ", got " +
                          (v.is_string() ? "\"" + v.get<std::string>() + "\"" : type_name(v)));
}

bool FieldReader::boolean(const Json& v, const std::string& ptr) const {
    if (!v.is_boolean())
        schema_error(ptr, std::string("expected true or false, got ") + type_name(v));
    return v.get<bool>();
}

float FieldReader::number(const Json& v, const std::string& ptr) {
    if (!v.is_number()) schema_error(ptr, std::string("expected a number, got ") + type_name(v));
    const double d = v.get<double>();
    if (!fits_float(d)) {
        record_value_error(ptr, "number is not finite as a 32-bit float", ErrorCode::NotFinite);
        return 0.0f;
    }
    return static_cast<float>(d);
}

float FieldReader::positive_number(const Json& v, const std::string& ptr) {
    if (v.is_number() && !(v.get<double>() > 0.0)) schema_error(ptr, "expected a number > 0");
    return number(v, ptr);
}

uint64_t FieldReader::integer(const Json& v, const std::string& ptr, uint64_t lo,
                              uint64_t hi) const {
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (v.is_number_unsigned() || v.is_number_integer()) {
        if (v.is_number_integer() && v.get<int64_t>() < 0)
            schema_error(ptr, "expected an integer in " + range);
        const uint64_t u = v.get<uint64_t>();
        if (u < lo || u > hi) schema_error(ptr, "expected an integer in " + range);
        return u;
    }
    if (v.is_number_float()) {
        const double d = v.get<double>();
        if (std::floor(d) != d) schema_error(ptr, "expected an integer, got a fraction");
        if (d < double(lo) || d > double(hi)) schema_error(ptr, "expected an integer in " + range);
        return static_cast<uint64_t>(d);
    }
    schema_error(ptr, std::string("expected an integer, got ") + type_name(v));
}

std::size_t FieldReader::array_size(const Json& v, const std::string& ptr, const char* what) const {
    if (is_packed_numbers(v)) return packed_size(v);
    if (!v.is_array()) schema_error(ptr, std::string("expected ") + what + ", got " + type_name(v));
    return v.size();
}

double FieldReader::array_number(const Json& v, std::size_t i, const std::string& ptr) const {
    if (is_packed_numbers(v)) return packed_value(v, i);
    const Json& e = v[i];
    if (!e.is_number())
        schema_error(child(ptr, i), std::string("expected a number, got ") + type_name(e));
    return e.get<double>();
}

template <class Vec>
Vec FieldReader::fixed_numbers(const Json& v, const std::string& ptr) {
    constexpr int N = Vec::length();
    static const std::string what = "an array of " + std::to_string(N) + " numbers";
    if (array_size(v, ptr, what.c_str()) != std::size_t(N))
        schema_error(ptr, "expected an array of exactly " + std::to_string(N) + " numbers");
    Vec out;
    for (int k = 0; k < N; ++k) out[k] = number(v[k], child(ptr, std::size_t(k)));
    return out;
}

Vec3 FieldReader::vec3(const Json& v, const std::string& ptr) {
    return fixed_numbers<Vec3>(v, ptr);
}

Vec4 FieldReader::vec4(const Json& v, const std::string& ptr) {
    return fixed_numbers<Vec4>(v, ptr);
}

std::vector<float> FieldReader::floats(const Json& v, const std::string& ptr) {
    const std::size_t n = array_size(v, ptr, "an array of numbers");
    std::vector<float> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double d = array_number(v, i, ptr);
        if (!fits_float(d))
            record_value_error(child(ptr, i), "number is not finite as a 32-bit float",
                               ErrorCode::NotFinite);
        out[i] = static_cast<float>(d);
    }
    return out;
}

namespace {

/// The floats of one per-vertex value: 1 for a plain float (a radius), else its vector length.
template <class V>
constexpr std::size_t components() {
    if constexpr (std::is_same_v<V, float>)
        return 1;
    else
        return std::size_t(V::length());
}
template <class V>
float& component(V& v, std::size_t k) {
    if constexpr (std::is_same_v<V, float>)
        return v;
    else
        return v[int(k)];
}

}  // namespace

template <class V>
std::vector<V> FieldReader::per_vertex(const Json& v, const std::string& ptr,
                                       std::string_view field) {
    constexpr std::size_t n = components<V>();
    static constexpr const char* LAYOUT[] = {"", "one", "u v", "x y z", "x y z w"};
    const std::vector<float> flat = floats(v, ptr);
    if (flat.size() % n != 0)
        record_value_error(ptr, std::string(field) + " has " + std::to_string(flat.size()) +
                                    " numbers, not a multiple of " + std::to_string(n) + " (" +
                                    LAYOUT[n] + " per vertex)");
    std::vector<V> out(flat.size() / n);
    for (std::size_t i = 0; i < out.size(); ++i)
        for (std::size_t k = 0; k < n; ++k) component(out[i], k) = flat[n * i + k];
    return out;
}
template std::vector<float> FieldReader::per_vertex(const Json&, const std::string&,
                                                    std::string_view);
template std::vector<Vec2> FieldReader::per_vertex(const Json&, const std::string&,
                                                   std::string_view);
template std::vector<Vec3> FieldReader::per_vertex(const Json&, const std::string&,
                                                   std::string_view);
template std::vector<Vec4> FieldReader::per_vertex(const Json&, const std::string&,
                                                   std::string_view);

std::vector<Vec3> FieldReader::positions(const Json& v, const std::string& ptr) {
    return per_vertex<Vec3>(v, ptr, "positions");
}

std::vector<Triangle> FieldReader::indices(const Json& v, const std::string& ptr) {
    const std::size_t n = array_size(v, ptr, "a flat array of integers");
    std::vector<Triangle> out(n / 3);
    uint32_t* dst = reinterpret_cast<uint32_t*>(out.data());
    const std::size_t whole = out.size() * 3;
    for (std::size_t i = 0; i < n; ++i) {
        const double d = array_number(v, i, ptr);
        if (!(d >= 0.0 && d <= 4294967295.0) || std::floor(d) != d)
            schema_error(child(ptr, i), "expected an integer in [0, 4294967295]");
        if (i < whole) dst[i] = static_cast<uint32_t>(d);
    }
    if (n % 3 != 0)
        record_value_error(ptr, "indices has " + std::to_string(n) +
                                    " numbers, not a multiple of 3 (one triple per triangle)");
    return out;
}

std::vector<uint32_t> FieldReader::vertex_ids(const Json& v, const std::string& ptr) {
    const std::size_t n = array_size(v, ptr, "a flat array of integers");
    std::vector<uint32_t> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const double d = array_number(v, i, ptr);
        if (!(d >= 0.0 && d <= 4294967295.0) || std::floor(d) != d)
            schema_error(child(ptr, i), "expected an integer in [0, 4294967295]");
        out[i] = static_cast<uint32_t>(d);
    }
    return out;
}

std::string FieldReader::base64_bytes(const Json& v, const std::string& ptr, std::size_t unit) {
    if (!v.is_string())
        schema_error(ptr, std::string("expected a base64 string, got ") + type_name(v));
    std::size_t bad_at = 0;
    auto bytes = decode_base64(v.get_ref<const std::string&>(), &bad_at);
    if (!bytes) {
        if (bad_at == v.get_ref<const std::string&>().size())
            schema_error(ptr, "base64 length is not a multiple of 4");
        schema_error(ptr, "invalid base64 character at offset " + std::to_string(bad_at));
    }
    if (bytes->size() % unit != 0) {
        record_value_error(ptr, "decoded " + std::to_string(bytes->size()) +
                                    " bytes, not a multiple of " + std::to_string(unit));
        bytes->resize(bytes->size() / unit * unit);
    }
    return std::move(*bytes);
}

template <class V>
std::vector<V> FieldReader::per_vertex_b64(const Json& v, const std::string& ptr,
                                           std::string_view field) {
    constexpr std::size_t size = components<V>() * sizeof(float);
    const std::string bytes = base64_bytes(v, ptr, size);
    std::vector<V> out(bytes.size() / size);
    for (std::size_t i = 0; i < out.size(); ++i) {
        for (std::size_t k = 0; k < components<V>(); ++k)
            component(out[i], k) = load_le<float>(bytes.data() + i * size + k * sizeof(float));
        bool finite = true;
        for (std::size_t k = 0; k < components<V>(); ++k)
            finite = finite && std::isfinite(component(out[i], k));
        if (!finite)
            record_value_error(ptr,
                               "vertex " + std::to_string(i) + " of " + std::string(field) +
                                   " has a NaN or infinite component",
                               ErrorCode::NotFinite);
    }
    return out;
}
template std::vector<float> FieldReader::per_vertex_b64(const Json&, const std::string&,
                                                        std::string_view);
template std::vector<Vec2> FieldReader::per_vertex_b64(const Json&, const std::string&,
                                                       std::string_view);
template std::vector<Vec3> FieldReader::per_vertex_b64(const Json&, const std::string&,
                                                       std::string_view);
template std::vector<Vec4> FieldReader::per_vertex_b64(const Json&, const std::string&,
                                                       std::string_view);

std::vector<Vec3> FieldReader::positions_b64(const Json& v, const std::string& ptr) {
    return per_vertex_b64<Vec3>(v, ptr, "positions");
}

std::vector<Affine> FieldReader::transforms_b64(const Json& v, const std::string& ptr) {
    const std::string bytes = base64_bytes(v, ptr, sizeof(Affine));
    std::vector<Affine> out(bytes.size() / sizeof(Affine));
    for (std::size_t i = 0; i < out.size(); ++i) {
        for (std::size_t k = 0; k < 12; ++k)
            out[i].m[k] = load_le<float>(bytes.data() + i * sizeof(Affine) + k * 4);
    }
    return out;
}

std::vector<Triangle> FieldReader::indices_b64(const Json& v, const std::string& ptr) {
    const std::string bytes = base64_bytes(v, ptr, 12);
    std::vector<Triangle> out(bytes.size() / 12);
    for (std::size_t i = 0; i < out.size(); ++i) {
        for (int k = 0; k < 3; ++k) out[i][k] = load_le<uint32_t>(bytes.data() + i * 12 + k * 4);
    }
    return out;
}

std::vector<uint32_t> FieldReader::vertex_ids_b64(const Json& v, const std::string& ptr) {
    const std::string bytes = base64_bytes(v, ptr, 4);
    std::vector<uint32_t> out(bytes.size() / 4);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = load_le<uint32_t>(bytes.data() + i * 4);
    return out;
}

}  // namespace strata::protocol

#pragma once
// Typed reads of request fields with exact JSON pointers in every error. Schema errors (wrong
// type, missing or unknown member, out-of-schema range) are thrown as RequestFailure and stop the
// parse; value errors (well-formed but unusable, such as a number that overflows a float) are
// recorded, the first one kept, and the parse goes on, so a schema error anywhere in a request
// always wins. That keeps the parser's structural verdict equal to the JSON Schema's.

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/utf8.h"
#include "engine/scene/types.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// Longest id, in Unicode code points (the schema's maxLength).
constexpr std::size_t MAX_ID_LENGTH = MAX_ID_CODE_POINTS;

/// The members an object may have and those it must have, in schema order (read from a JSON
/// Schema object's `properties` and `required`: see edit_schema.h).
struct MemberRule {
    std::vector<std::string> allowed;
    std::vector<std::string> required;

    /// True when `key` is one of `allowed`.
    bool allows(std::string_view key) const;
};

/// Most triangles the procedural shapes of one batch may generate: a shape is a few bytes of
/// JSON for up to millions of triangles, generated while parsing, before any budget is checked.
constexpr uint64_t MAX_SHAPE_TRIANGLES_PER_BATCH = uint64_t(1) << 24;

class FieldReader {
public:
    /// Edit index copied into the errors raised from now on (NO_INDEX outside a batch).
    void set_edit_index(std::size_t i) { m_edit_index = i; }
    std::size_t edit_index() const { return m_edit_index; }

    /// The first value error recorded, if any.
    const std::optional<Problem>& value_error() const { return m_value_error; }
    /// Records a value error unless one is already recorded.
    void record_value_error(std::string pointer, std::string message,
                            ErrorCode code = ErrorCode::InvalidArgument);

    /// Requires an object with no members beyond `allowed`.
    void expect_object(const Json& v, const std::string& ptr,
                       std::initializer_list<std::string_view> allowed) const;
    /// Requires an object with no members beyond `rule.allowed` and every one of
    /// `rule.required` (the first missing one, in the rule's order, is the error).
    void expect_object(const Json& v, const std::string& ptr, const MemberRule& rule) const;
    /// The member, or nullptr when absent.
    static const Json* member(const Json& obj, std::string_view key);
    /// The member; a schema error when absent.
    const Json& required(const Json& obj, const std::string& ptr, std::string_view key) const;

    /// A non-empty string of at most MAX_ID_LENGTH code points.
    std::string id(const Json& v, const std::string& ptr) const;
    /// Any string (free text: the scene checks its rules).
    std::string text(const Json& v, const std::string& ptr) const;
    /// One of `choices`; returns its position.
    std::size_t choice(const Json& v, const std::string& ptr,
                       std::initializer_list<std::string_view> choices) const;
    std::size_t choice(const Json& v, const std::string& ptr,
                       std::span<const std::string_view> choices) const;
    bool boolean(const Json& v, const std::string& ptr) const;
    /// Any JSON number, as a float; a value error when it does not fit a finite float.
    float number(const Json& v, const std::string& ptr);
    /// A number > 0 (schema), finite as a float (value).
    float positive_number(const Json& v, const std::string& ptr);
    /// An integer (3.0 counts, as in JSON Schema) in [lo, hi].
    uint64_t integer(const Json& v, const std::string& ptr, uint64_t lo, uint64_t hi) const;
    /// An array of exactly N numbers.
    Vec3 vec3(const Json& v, const std::string& ptr);
    Vec4 vec4(const Json& v, const std::string& ptr);
    /// Array of numbers (any length, packed or not), each a finite float.
    std::vector<float> floats(const Json& v, const std::string& ptr);
    /// Flat array of numbers, 3 per vertex.
    std::vector<Vec3> positions(const Json& v, const std::string& ptr);
    /// Flat array of non-negative 32-bit integers, 3 per triangle.
    std::vector<Triangle> indices(const Json& v, const std::string& ptr);
    /// Base64 little-endian float32 triples.
    std::vector<Vec3> positions_b64(const Json& v, const std::string& ptr);
    /// A per-vertex attribute `field` of V::length() floats a vertex: a flat array of numbers,
    /// or base64 little-endian float32s (each vertex finite).
    template <class V>
    std::vector<V> per_vertex(const Json& v, const std::string& ptr, std::string_view field);
    template <class V>
    std::vector<V> per_vertex_b64(const Json& v, const std::string& ptr, std::string_view field);
    /// Base64 little-endian uint32 triples.
    std::vector<Triangle> indices_b64(const Json& v, const std::string& ptr);
    /// Vertex indices: a flat array of non-negative 32-bit integers, or base64 little-endian
    /// uint32s.
    std::vector<uint32_t> vertex_ids(const Json& v, const std::string& ptr);
    std::vector<uint32_t> vertex_ids_b64(const Json& v, const std::string& ptr);
    /// Base64 little-endian float32 3x4 row-major transforms, 48 bytes each (the scene checks
    /// their values).
    std::vector<Affine> transforms_b64(const Json& v, const std::string& ptr);

    [[noreturn]] void schema_error(const std::string& ptr, std::string message) const;

    /// Counts `triangles` a procedural shape at `ptr` is about to generate. Returns false, having
    /// recorded a TooLarge value error, when the batch's shapes would exceed
    /// MAX_SHAPE_TRIANGLES_PER_BATCH: then generate nothing.
    bool reserve_shape_triangles(uint64_t triangles, const std::string& ptr);
    /// A base64 string of any bytes (an image file).
    std::string bytes_b64(const Json& v, const std::string& ptr) { return base64_bytes(v, ptr, 1); }

private:
    template <class Names>
    void expect_known_members(const Json& v, const std::string& ptr, const Names& allowed) const;
    /// Element count of a JSON or packed array (schema error when `v` is neither).
    std::size_t array_size(const Json& v, const std::string& ptr, const char* what) const;
    /// Element `i` of a JSON or packed array as a double (schema error for a non-number).
    double array_number(const Json& v, std::size_t i, const std::string& ptr) const;
    /// An array of exactly Vec::length() numbers (vec3, vec4).
    template <class Vec>
    Vec fixed_numbers(const Json& v, const std::string& ptr);
    std::string base64_bytes(const Json& v, const std::string& ptr, std::size_t unit);

    std::size_t m_edit_index = Error::NO_INDEX;
    std::optional<Problem> m_value_error;
    uint64_t m_shape_triangles = 0;
};

/// "ptr/key" with the key escaped as a JSON pointer token.
std::string child(const std::string& ptr, std::string_view key);
/// "ptr/index".
std::string child(const std::string& ptr, std::size_t index);

}  // namespace strata::protocol

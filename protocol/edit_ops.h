#pragma once
// The edit ops of the wire protocol, each described once by an EditOp: its wire name, a one-line
// doc, its JSON Schema fragment, its parser, and the alternatives of the engine's `Edit` that the
// parser produces. The ops live by family in protocol/ops/*.cpp; edit_ops() lists them all, and
// everything else is derived from that list: the dispatch in edit_parser.cpp, the members each op
// accepts, protocol/edit-batch.schema.json (edit_schema.h) and the ops index of
// protocol/README.md (tests/protocol/protocol_docs_test.cpp).
//
// Adding an op: its struct in engine/scene/edits.h and its rule in engine/scene/scene_rules.cpp
// (check, then change, saving what it overwrites for undo: undo_log.h); its journal layout, a
// `fields()` in engine/durable/edit_codec.cpp (append the kind to the Edit variant, never insert);
// an EditOp with its parser in a family file of protocol/ops/; its JSON in protocol/scene_json.cpp
// when it makes a new kind of object; a `### ` section with a ```json example in
// protocol/README.md; valid and invalid cases in tests/protocol/batches.json; then
// `STRATA_UPDATE_DOCS=1 ctest --test-dir build -R ProtocolDocs` regenerates the schema file and the
// README's index. An object kind's plain fields are not written in any of those places: they are
// rows of its field table (engine/scene/object_fields.h), which the rules, undo log, codec,
// parser, JSON writer, schema and docs all walk.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "engine/core/math.h"
#include "engine/scene/edits.h"
#include "protocol/edit_parser.h"
#include "protocol/edit_schema.h"
#include "protocol/json_fields.h"

namespace strata::protocol {

/// A set of `Edit` alternatives, one bit per variant index.
using EditKinds = uint64_t;
static_assert(std::variant_size_v<Edit> <= 64, "EditKinds has one bit per Edit alternative");

namespace detail {
template <class T, class V>
struct VariantIndex;
template <class T, class... Ts>
struct VariantIndex<T, std::variant<Ts...>> {
    static constexpr std::size_t value = [] {
        constexpr bool same[] = {std::is_same_v<T, Ts>...};
        for (std::size_t i = 0; i < sizeof...(Ts); ++i) {
            if (same[i]) return i;
        }
        return sizeof...(Ts);
    }();
};
}  // namespace detail

/// The set of the alternatives `Ts`, each of which must be one of `Edit`.
template <class... Ts>
constexpr EditKinds edit_kinds() {
    static_assert(((detail::VariantIndex<Ts, Edit>::value < std::variant_size_v<Edit>)&&...),
                  "not an alternative of strata::Edit");
    return ((EditKinds{1} << detail::VariantIndex<Ts, Edit>::value) | ...);
}

/// The alternative an edit holds, as a one-element set.
inline EditKinds edit_kind(const Edit& e) {
    return EditKinds{1} << e.index();
}

class OpFields;

/// Turns one op object into an engine edit.
using OpParser = Edit (*)(OpFields&);
/// The schema properties an op takes from an object kind's field table (field_json.h).
using OpFieldProperties = OrderedJson (*)();

/// One op: the single place its name, documentation, schema and parser are written.
struct EditOp {
    std::string_view name;  ///< the value of the `op` member
    /// One sentence: the README's ops index and the schema's `description` of the op.
    std::string_view doc;
    /// The op object's JSON Schema without `op` and `description`, which the generator adds
    /// (`"op": {"const": name}` first in `properties` and in `required`). `$ref`s point into the
    /// shared `$defs` of edit_schema.cpp.
    std::string_view schema;
    OpParser parse;
    EditKinds produces;  ///< every alternative `parse` may return
    /// When set, the properties of a kind's fields, added after those of `schema`.
    OpFieldProperties fields = nullptr;
};

/// Every op, in the order of the schema and the README.
std::span<const EditOp> edit_ops();
/// The op named `name`, or nullptr.
const EditOp* find_edit_op(std::string_view name);
/// The members op `op` (an element of edit_ops()) accepts and requires, from its schema.
const MemberRule& edit_op_members(const EditOp& op);

/// The op object a parser reads. Before the parser runs, the object's members have been checked
/// against the op's schema (nothing unknown, every required member present), so a parser only
/// fetches and converts; every member it asks for must be one its schema declares (checked in
/// debug builds).
class OpFields {
public:
    OpFields(FieldReader& r, const Json& v, const std::string& ptr, const MemberRule& members,
             EditSource& source);

    FieldReader& reader() const { return m_r; }
    /// Where the parser records which wire members its arrays came from.
    EditSource& source() const { return m_source; }
    /// The JSON pointer of the op object.
    const std::string& pointer() const { return m_ptr; }
    /// The JSON pointer of member `key`.
    std::string pointer(std::string_view key) const { return child(m_ptr, key); }

    /// Member `key`, or nullptr when absent.
    const Json* get(std::string_view key) const;
    /// Member `key`, which the schema requires.
    const Json& at(std::string_view key) const;
    /// The required id member `key`.
    std::string id(std::string_view key) const { return m_r.id(at(key), pointer(key)); }

    /// Reads member `key` into `out` when present and says whether it was. Strings are ids,
    /// floats any finite number, uint32_t an integer in [0, 2^32), Affine a transform.
    bool read(std::string_view key, std::string& out);
    bool read(std::string_view key, float& out);
    bool read(std::string_view key, bool& out);
    bool read(std::string_view key, uint32_t& out);
    bool read(std::string_view key, Vec3& out);
    bool read(std::string_view key, Affine& out);
    /// An array of transforms (motion keys), at most MAX_MOTION_KEYS.
    bool read(std::string_view key, std::vector<Affine>& out);
    bool read(std::string_view key, std::vector<Keyframe>& out);
    /// Free text (a display name), where read(std::string&) reads an id.
    bool read_text(std::string_view key, std::string& out);
    /// One of `choices`, stored as the enum value of its position.
    template <class E>
    requires std::is_enum_v<E>
    bool read(std::string_view key, E& out, std::span<const std::string_view> choices) {
        const Json* v = get(key);
        if (v) out = static_cast<E>(m_r.choice(*v, pointer(key), choices));
        return v;
    }
    template <class T>
    bool read(std::string_view key, std::optional<T>& out) {
        T value{};
        if (!read(key, value)) return false;
        out = std::move(value);
        return true;
    }

private:
    FieldReader& m_r;
    const Json& m_v;
    const std::string& m_ptr;
    const MemberRule& m_members;
    EditSource& m_source;
};

}  // namespace strata::protocol

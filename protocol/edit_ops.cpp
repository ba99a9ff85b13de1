#include "protocol/edit_ops.h"

#include <vector>

#include "engine/core/check.h"
#include "protocol/edit_schema.h"
#include "protocol/ops/families.h"
#include "protocol/transform_parser.h"

namespace strata::protocol {

std::span<const EditOp> edit_ops() {
    static const std::vector<EditOp> ops = [] {
        std::vector<EditOp> all;
        for (std::span<const EditOp> family :
             {ops::mesh_ops(), ops::texture_ops(), ops::material_ops(), ops::instance_ops(),
              ops::bulk_instance_ops(),
              ops::group_ops(), ops::light_ops(), ops::scene_ops()})
            all.insert(all.end(), family.begin(), family.end());
        return all;
    }();
    return ops;
}

const EditOp* find_edit_op(std::string_view name) {
    for (const EditOp& op : edit_ops()) {
        if (op.name == name) return &op;
    }
    return nullptr;
}

const MemberRule& edit_op_members(const EditOp& op) {
    static const std::vector<MemberRule> members = [] {
        std::vector<MemberRule> m;
        for (const EditOp& o : edit_ops())
            m.push_back(schema_members("/$defs/" + std::string(o.name)));
        return m;
    }();
    const std::span<const EditOp> ops = edit_ops();
    STRATA_DCHECK(&op >= ops.data() && &op < ops.data() + ops.size());
    return members[std::size_t(&op - ops.data())];
}

OpFields::OpFields(FieldReader& r, const Json& v, const std::string& ptr, const MemberRule& members,
                   EditSource& source)
    : m_r(r), m_v(v), m_ptr(ptr), m_members(members), m_source(source) {}

const Json* OpFields::get(std::string_view key) const {
    STRATA_DCHECK(m_members.allows(key));
    return FieldReader::member(m_v, key);
}

const Json& OpFields::at(std::string_view key) const {
    STRATA_DCHECK(m_members.allows(key));
    return m_r.required(m_v, m_ptr, key);
}

namespace {

/// Converts member `key` into `out` with `convert(json, pointer)` when present.
template <class T, class Convert>
bool read_member(const OpFields& f, std::string_view key, T& out, Convert convert) {
    const Json* v = f.get(key);
    if (v) out = convert(*v, f.pointer(key));
    return v;
}

}  // namespace

bool OpFields::read(std::string_view key, std::string& out) {
    return read_member(*this, key, out,
                       [&](const Json& v, const std::string& p) { return m_r.id(v, p); });
}

bool OpFields::read_text(std::string_view key, std::string& out) {
    return read_member(*this, key, out,
                       [&](const Json& v, const std::string& p) { return m_r.text(v, p); });
}

bool OpFields::read(std::string_view key, float& out) {
    return read_member(*this, key, out,
                       [&](const Json& v, const std::string& p) { return m_r.number(v, p); });
}

bool OpFields::read(std::string_view key, bool& out) {
    return read_member(*this, key, out,
                       [&](const Json& v, const std::string& p) { return m_r.boolean(v, p); });
}

bool OpFields::read(std::string_view key, uint32_t& out) {
    return read_member(*this, key, out, [&](const Json& v, const std::string& p) {
        return static_cast<uint32_t>(m_r.integer(v, p, 0, UINT32_MAX));
    });
}

bool OpFields::read(std::string_view key, Vec3& out) {
    return read_member(*this, key, out,
                       [&](const Json& v, const std::string& p) { return m_r.vec3(v, p); });
}

bool OpFields::read(std::string_view key, Affine& out) {
    return read_member(*this, key, out, [&](const Json& v, const std::string& p) {
        return parse_transform(m_r, v, p);
    });
}

bool OpFields::read(std::string_view key, std::vector<Affine>& out) {
    return read_member(*this, key, out, [&](const Json& v, const std::string& p) {
        if (!v.is_array() || v.size() > MAX_MOTION_KEYS)
            m_r.schema_error(p, "expected an array of at most " + std::to_string(MAX_MOTION_KEYS) +
                                    " transforms");
        std::vector<Affine> keys;
        keys.reserve(v.size());
        for (std::size_t k = 0; k < v.size(); ++k)
            keys.push_back(parse_transform(m_r, v[k], child(p, k)));
        return keys;
    });
}

bool OpFields::read(std::string_view key, std::vector<Keyframe>& out) {
    return read_member(*this, key, out, [&](const Json& v, const std::string& p) {
        if (!v.is_array() || v.size() > MAX_ANIMATION_KEYS)
            m_r.schema_error(p, "expected an array of at most " +
                                    std::to_string(MAX_ANIMATION_KEYS) + " keyframes");
        std::vector<Keyframe> keys(v.size());
        for (std::size_t k = 0; k < v.size(); ++k) {
            const std::string kp = child(p, k);
            static const MemberRule KEY = schema_members("/$defs/keyframe");
            m_r.expect_object(v[k], kp, KEY);
            keys[k].time = m_r.number(m_r.required(v[k], kp, "time"), child(kp, "time"));
            keys[k].transform =
                parse_transform(m_r, m_r.required(v[k], kp, "transform"), child(kp, "transform"));
        }
        return keys;
    });
}

}  // namespace strata::protocol

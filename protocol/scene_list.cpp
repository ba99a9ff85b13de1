// GET /v1/scene/{meshes,instances,materials,groups,lights,textures}: paginated listings.
//
// Pages walk the collection in slot order, which never changes while an object exists: an object
// that exists for the whole walk appears exactly once, and objects added or removed during the
// walk may or may not appear. The cursor names the slot the next page starts at; it is opaque
// to clients (and checked: a cursor of another collection, or a made-up one, is refused).
// A `parent=` filter naming a group pages through that group's children in the same slot order
// (sorted per page: the cost follows the group, not the scene); `parent=` empty is the root.

#include <algorithm>
#include <charconv>
#include <unordered_map>

#include "protocol/api.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

namespace {

constexpr uint32_t DEFAULT_PAGE = 100;
constexpr uint32_t MAX_PAGE = 10000;

constexpr const char* COLLECTIONS[] = {"meshes", "instances", "materials",
                                       "groups", "lights",    "textures"};

struct ListQuery {
    uint32_t limit = DEFAULT_PAGE;
    uint32_t first_slot = 0;
    std::optional<std::string> mesh;    ///< instances: only those of this mesh
    std::optional<bool> visible;        ///< instances: only (in)visible ones
    std::optional<std::string> parent;  ///< instances, groups: only children of (empty: root)
};

Problem bad_query(const std::string& parameter, std::string message) {
    Problem p = make_problem(ProblemType::InvalidRequest, std::move(message));
    p.pointer = "/" + parameter;
    return p;
}

std::string encode_cursor(SceneObject kind, uint32_t slot) {
    char hex[16];
    const auto end = std::to_chars(hex, hex + sizeof hex, slot, 16).ptr;
    return std::string(COLLECTIONS[int(kind)]) + "-" + std::string(hex, end);
}

std::optional<uint32_t> decode_cursor(SceneObject kind, std::string_view cursor) {
    const std::string_view prefix = COLLECTIONS[int(kind)];
    if (cursor.size() <= prefix.size() + 1 || cursor.substr(0, prefix.size()) != prefix ||
        cursor[prefix.size()] != '-')
        return std::nullopt;
    const std::string_view hex = cursor.substr(prefix.size() + 1);
    uint32_t slot = 0;
    const auto [end, ec] = std::from_chars(hex.data(), hex.data() + hex.size(), slot, 16);
    if (ec != std::errc() || end != hex.data() + hex.size()) return std::nullopt;
    return slot;
}

std::optional<ListQuery> parse_list_query(SceneObject kind,
                                          const std::multimap<std::string, std::string>& query,
                                          Problem& problem) {
    ListQuery q;
    const bool instances = kind == SceneObject::Instance;
    const bool graph = instances || kind == SceneObject::Group;
    for (const auto& [key, text] : query) {
        if (query.count(key) > 1) {
            problem = bad_query(key, "query parameter '" + key + "' is given more than once");
            return std::nullopt;
        }
        if (key == "limit") {
            uint32_t n = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
            if (ec != std::errc() || end != text.data() + text.size() || n < 1 || n > MAX_PAGE) {
                problem = bad_query(
                    key, "limit must be an integer from 1 to " + std::to_string(MAX_PAGE));
                return std::nullopt;
            }
            q.limit = n;
        } else if (key == "cursor") {
            const auto slot = decode_cursor(kind, text);
            if (!slot) {
                problem = bad_query(key, std::string("cursor is not one a page of ") +
                                             COLLECTIONS[int(kind)] + " gave out");
                return std::nullopt;
            }
            q.first_slot = *slot;
        } else if (instances && key == "mesh") {
            q.mesh = text;
        } else if (instances && key == "visible") {
            if (text != "true" && text != "false") {
                problem = bad_query(key, "visible must be true or false");
                return std::nullopt;
            }
            q.visible = text == "true";
        } else if (graph && key == "parent") {
            q.parent = text;
        } else {
            problem = bad_query(key, "unknown query parameter '" + key +
                                         "': " + COLLECTIONS[int(kind)] + " take " +
                                         (instances ? "limit, cursor, mesh, visible and parent"
                                          : graph   ? "limit, cursor and parent"
                                                    : "limit and cursor"));
            return std::nullopt;
        }
    }
    return q;
}

/// The slots of `handles`, sorted: a child list in the listings' slot order.
template <class H>
std::vector<uint32_t> sorted_slots(const std::vector<H>& handles) {
    std::vector<uint32_t> slots;
    slots.reserve(handles.size());
    for (H h : handles) slots.push_back(h.index);
    std::sort(slots.begin(), slots.end());
    return slots;
}

/// One page of `objects` from q.first_slot: up to q.limit documents of the objects `keep`
/// accepts, and the cursor of the next accepted object, or null when there is none. With `only`,
/// just those slots (sorted) are visited, instead of every slot.
template <class Objects, class Keep, class ToJson>
Json page(SceneObject kind, const Objects& objects, const ListQuery& q, Keep&& keep,
          ToJson&& to_json, const std::vector<uint32_t>* only = nullptr) {
    Json items = Json::array();
    Json next = nullptr;
    auto visit = [&](uint32_t slot) {
        if (!objects.alive_at(slot) || !keep(objects.at_slot(slot))) return true;
        if (items.size() == q.limit) {
            next = encode_cursor(kind, slot);
            return false;
        }
        items.push_back(to_json(objects.handle_at(slot), objects.at_slot(slot)));
        return true;
    };
    if (only) {
        for (auto it = std::lower_bound(only->begin(), only->end(), q.first_slot);
             it != only->end() && visit(*it); ++it) {
        }
    } else {
        for (uint32_t slot = q.first_slot; slot < objects.slot_count() && visit(slot); ++slot) {
        }
    }
    return Json{{"items", std::move(items)}, {"next_cursor", std::move(next)}};
}

Problem no_group(const std::string& id, const char* parameter) {
    Problem p = make_problem(ProblemType::NotFound, "no group with id '" + id + "'");
    p.pointer = std::string("/") + parameter;
    return p;
}

/// Where a listing walks: every slot, or a group's children (`only`, sorted slots); and whether
/// it keeps only the objects at the root (`parent=`).
struct Walk {
    std::vector<uint32_t> children;
    bool by_parent = false;
    bool root_only = false;
    const std::vector<uint32_t>* only() const { return by_parent ? &children : nullptr; }
};

/// The page of a kind other than instances.
Json kind_page(SceneObject kind, const Scene& s, const ListQuery& q, const Walk& walk) {
    switch (kind) {
        case SceneObject::Mesh:
            return page(
                kind, s.meshes(), q, [](const MeshRecord&) { return true; },
                [&](MeshHandle h, const MeshRecord& m) { return mesh_json(s, h, m); });
        case SceneObject::Material:
            return page(
                kind, s.materials(), q, [](const MaterialRecord&) { return true; },
                [&](MaterialHandle, const MaterialRecord& m) { return material_json(s, m); });
        case SceneObject::Light:
            return page(
                kind, s.lights(), q, [](const LightRecord&) { return true; },
                [&](LightHandle, const LightRecord& l) { return light_json(s, l); });
        case SceneObject::Texture:
            return page(
                kind, s.textures(), q, [](const TextureRecord&) { return true; },
                [&](TextureHandle, const TextureRecord& t) { return texture_json(s, t); });
        case SceneObject::Group:
        case SceneObject::Instance:
            break;
    }
    return page(
        kind, s.groups(), q,
        [&](const GroupRecord& g) { return !walk.root_only || g.parent.is_null(); },
        [&](GroupHandle h, const GroupRecord& g) { return group_json(s, h, g); }, walk.only());
}

/// The page of instances, filtered by mesh, visibility and parent; nullopt when the mesh filter
/// names no mesh (`missing` says so).
std::optional<Json> instance_page(const Scene& s, const ListQuery& q, const Walk& walk,
                                  std::optional<Problem>& missing) {
    MeshHandle mesh;
    if (q.mesh) {
        mesh = s.find_mesh(*q.mesh);
        if (!s.mesh(mesh)) {
            Problem p = make_problem(ProblemType::NotFound, "no mesh with id '" + *q.mesh + "'");
            p.pointer = "/mesh";
            missing = p;
            return std::nullopt;
        }
    }
    // Object-space bounds once per mesh, not once per instance.
    std::unordered_map<uint32_t, Bounds3> bounds;
    return page(
        SceneObject::Instance, s.instances(), q,
        [&](const InstanceRecord& i) {
            return (!q.mesh || i.mesh == mesh) && (!q.visible || i.visible == *q.visible) &&
                   (!walk.root_only || i.parent.is_null());
        },
        [&](InstanceHandle h, const InstanceRecord& i) {
            auto [it, fresh] = bounds.try_emplace(i.mesh.index);
            if (fresh) it->second = mesh_bounds(*s.mesh(i.mesh).value());
            return instance_json(s, h, i, it->second);
        },
        walk.only());
}

}  // namespace

ApiResponse get_scene_list(const Engine& engine, SceneObject kind,
                           const std::multimap<std::string, std::string>& query) {
    Problem problem;
    const auto q = parse_list_query(kind, query, problem);
    if (!q) return problem_response(problem);
    // One read lock: every item and the page's version belong together.
    std::optional<Problem> missing;
    auto [doc, version] = engine.read([&](const Scene& s) -> std::pair<Json, uint64_t> {
        // parent=: a group's children (sorted slots), or the root's (a filtered walk).
        Walk walk;
        walk.root_only = q->parent && q->parent->empty();
        if (q->parent && !q->parent->empty()) {
            const GroupHandle parent = s.find_group(*q->parent);
            if (!s.group(parent)) {
                missing = no_group(*q->parent, "parent");
                return {nullptr, s.version()};
            }
            walk.by_parent = true;
            walk.children = kind == SceneObject::Group ? sorted_slots(s.children(parent).groups)
                                                       : sorted_slots(s.children(parent).instances);
        }
        if (kind != SceneObject::Instance) return {kind_page(kind, s, *q, walk), s.version()};
        std::optional<Json> items = instance_page(s, *q, walk, missing);
        return {items ? std::move(*items) : Json(nullptr), s.version()};
    });
    if (missing) return with_etag(problem_response(*missing), version);
    doc["version"] = version;
    return with_etag(json_response(200, doc), version);
}

}  // namespace strata::protocol

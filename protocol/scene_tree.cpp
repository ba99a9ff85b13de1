// GET /v1/scene/groups/{id}/children (one page of a group's groups, then its instances, each in
// slot order like every listing) and GET /v1/scene/tree (the scene graph nested to a depth, with
// a bound on the nodes it holds, for viewers that show an outline).

#include <algorithm>
#include <charconv>
#include <unordered_map>

#include "protocol/api.h"
#include "protocol/field_json.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

namespace {

constexpr uint32_t DEFAULT_PAGE = 100;
constexpr uint32_t MAX_PAGE = 10000;
constexpr uint32_t DEFAULT_TREE_DEPTH = 1;
constexpr uint32_t DEFAULT_TREE_NODES = 1000;
constexpr uint32_t MAX_TREE_NODES = 10000;

Problem bad_query(const std::string& parameter, std::string message) {
    Problem p = make_problem(ProblemType::InvalidRequest, std::move(message));
    p.pointer = "/" + parameter;
    return p;
}

bool parse_u32(const std::string& text, uint32_t lo, uint32_t hi, uint32_t& out) {
    uint32_t n = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
    if (ec != std::errc() || end != text.data() + text.size() || n < lo || n > hi) return false;
    out = n;
    return true;
}

/// A children cursor: which list ('g' groups, 'i' instances) and the slot to start at.
struct ChildCursor {
    char list = 'g';
    uint32_t slot = 0;
};

std::string encode_child_cursor(char list, uint32_t slot) {
    char hex[16];
    const auto end = std::to_chars(hex, hex + sizeof hex, slot, 16).ptr;
    return std::string("children-") + list + std::string(hex, end);
}

std::optional<ChildCursor> decode_child_cursor(std::string_view text) {
    constexpr std::string_view PREFIX = "children-";
    if (text.size() <= PREFIX.size() + 1 || text.substr(0, PREFIX.size()) != PREFIX)
        return std::nullopt;
    ChildCursor c;
    c.list = text[PREFIX.size()];
    if (c.list != 'g' && c.list != 'i') return std::nullopt;
    const std::string_view hex = text.substr(PREFIX.size() + 1);
    const auto [end, ec] = std::from_chars(hex.data(), hex.data() + hex.size(), c.slot, 16);
    if (ec != std::errc() || end != hex.data() + hex.size()) return std::nullopt;
    return c;
}

template <class H>
std::vector<H> sorted_by_slot(std::vector<H> handles) {
    std::sort(handles.begin(), handles.end(),
              [](H a, H b) { return a.index < b.index; });
    return handles;
}

/// Checks that no parameter repeats and every one is in `allowed`.
std::optional<Problem> check_params(const std::multimap<std::string, std::string>& query,
                                    std::initializer_list<std::string_view> allowed,
                                    const char* what) {
    for (const auto& [key, text] : query) {
        if (query.count(key) > 1)
            return bad_query(key, "query parameter '" + key + "' is given more than once");
        if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
            std::string names;
            for (std::string_view a : allowed) names += (names.empty() ? "" : ", ") + std::string(a);
            return bad_query(key, "unknown query parameter '" + key + "': " + what + " take " +
                                      names);
        }
    }
    return std::nullopt;
}

}  // namespace

ApiResponse get_group_children(const Engine& engine, std::string_view id,
                               const std::multimap<std::string, std::string>& query) {
    if (auto p = check_params(query, {"limit", "cursor"}, "children")) return problem_response(*p);
    uint32_t limit = DEFAULT_PAGE;
    ChildCursor from;
    if (auto it = query.find("limit"); it != query.end() && !parse_u32(it->second, 1, MAX_PAGE, limit))
        return problem_response(
            bad_query("limit", "limit must be an integer from 1 to " + std::to_string(MAX_PAGE)));
    if (auto it = query.find("cursor"); it != query.end()) {
        const auto c = decode_child_cursor(it->second);
        if (!c)
            return problem_response(
                bad_query("cursor", "cursor is not one a page of children gave out"));
        from = *c;
    }
    auto [doc, version] = engine.read([&](const Scene& s) -> std::pair<Json, uint64_t> {
        const GroupHandle g = s.find_group(id);
        if (!s.group(g)) return {nullptr, s.version()};
        const Children& c = s.children(g);
        Json items = Json::array();
        Json next = nullptr;
        // Groups first, then instances; each list in slot order, from the cursor on.
        if (from.list == 'g') {
            for (GroupHandle h : sorted_by_slot(c.groups)) {
                if (h.index < from.slot) continue;
                if (items.size() == limit) {
                    next = encode_child_cursor('g', h.index);
                    break;
                }
                Json j = group_json(s, h, *s.group(h).value());
                j["kind"] = "group";
                items.push_back(std::move(j));
            }
        }
        if (next.is_null()) {
            std::unordered_map<uint32_t, Bounds3> bounds;
            for (InstanceHandle h : sorted_by_slot(c.instances)) {
                if (from.list == 'i' && h.index < from.slot) continue;
                if (items.size() == limit) {
                    next = encode_child_cursor('i', h.index);
                    break;
                }
                const InstanceRecord& i = *s.instance(h).value();
                auto [it, fresh] = bounds.try_emplace(i.mesh.index);
                if (fresh) it->second = mesh_bounds(*s.mesh(i.mesh).value());
                Json j = instance_json(s, h, i, it->second);
                j["kind"] = "instance";
                items.push_back(std::move(j));
            }
        }
        return {Json{{"items", std::move(items)},
                     {"next_cursor", std::move(next)},
                     {"version", s.version()}},
                s.version()};
    });
    if (doc.is_null())
        return with_etag(problem_response(make_problem(
                             ProblemType::NotFound, "no group with id '" + std::string(id) + "'")),
                         version);
    return with_etag(json_response(200, doc), version);
}

ApiResponse get_scene_tree(const Engine& engine,
                           const std::multimap<std::string, std::string>& query) {
    if (auto p = check_params(query, {"depth", "max_nodes", "group"}, "the tree"))
        return problem_response(*p);
    uint32_t depth = DEFAULT_TREE_DEPTH;
    uint32_t max_nodes = DEFAULT_TREE_NODES;
    if (auto it = query.find("depth");
        it != query.end() && !parse_u32(it->second, 0, MAX_GROUP_DEPTH, depth))
        return problem_response(bad_query(
            "depth", "depth must be an integer from 0 to " + std::to_string(MAX_GROUP_DEPTH)));
    if (auto it = query.find("max_nodes");
        it != query.end() && !parse_u32(it->second, 1, MAX_TREE_NODES, max_nodes))
        return problem_response(bad_query(
            "max_nodes",
            "max_nodes must be an integer from 1 to " + std::to_string(MAX_TREE_NODES)));
    const auto group_param = query.find("group");
    auto [doc, version] = engine.read([&](const Scene& s) -> std::pair<Json, uint64_t> {
        GroupHandle top;
        if (group_param != query.end()) {
            top = s.find_group(group_param->second);
            if (!s.group(top)) return {nullptr, s.version()};
        }
        uint32_t nodes = 0;
        bool truncated = false;
        // A node: its groups (nested while depth lasts) and its instances, each list cut where
        // the node budget runs out; `groups`/`instances` counts say how many there are in all.
        auto children_json = [&](auto& self, GroupHandle parent, uint32_t levels) -> Json {
            const Children& c = s.children(parent);
            Json groups = Json::array();
            Json instances = Json::array();
            for (GroupHandle h : c.groups) {
                if (nodes == max_nodes) {
                    truncated = true;
                    break;
                }
                ++nodes;
                const GroupRecord& g = *s.group(h).value();
                Json node{{"id", g.id},
                          {"visible", g.visible},
                          {"world_visible", g.world_visible},
                          {"group_count", g.children.groups.size()},
                          {"instance_count", g.children.instances.size()}};
                write_labels<GroupFields>(node, save_fields<GroupFields>(g));
                if (levels > 0) node.update(self(self, h, levels - 1));
                groups.push_back(std::move(node));
            }
            for (InstanceHandle h : c.instances) {
                if (nodes == max_nodes) {
                    truncated = true;
                    break;
                }
                ++nodes;
                const InstanceRecord& i = *s.instance(h).value();
                Json node{{"id", i.id},
                          {"mesh", s.mesh(i.mesh).value()->id},
                          {"visible", i.visible},
                          {"world_visible", i.world_visible}};
                write_labels<InstanceFields>(node, save_fields<InstanceFields>(i));
                instances.push_back(std::move(node));
            }
            return Json{{"groups", std::move(groups)}, {"instances", std::move(instances)}};
        };
        Json tree = children_json(children_json, top, depth);
        tree["version"] = s.version();
        tree["group"] = top.is_null() ? Json(nullptr) : Json(s.group(top).value()->id);
        tree["depth"] = depth;
        tree["truncated"] = truncated;
        return {std::move(tree), s.version()};
    });
    if (doc.is_null()) {
        Problem p =
            make_problem(ProblemType::NotFound, "no group with id '" + group_param->second + "'");
        p.pointer = "/group";
        return with_etag(problem_response(p), version);
    }
    return with_etag(json_response(200, doc), version);
}

}  // namespace strata::protocol

// `strata scene list`, `strata scene get`, `strata scene tree` and `strata pick`: reading the
// scene object by object or as an outline, and asking what lies under a pixel.

#include "clients/cli/commands.h"

#include <ostream>

namespace strata::cli {

namespace {

constexpr int OK = 0;
constexpr int BAD_INPUT = 2;

/// One line per listed object for people: its id, then what tells it apart.
std::string item_line(const std::string& collection, const Json& item) {
    std::string line = item.value("id", std::string("?"));
    if (collection == "instances") {
        line += "  mesh=" + item.value("mesh", std::string("?"));
        if (item.contains("material") && item["material"].is_string())
            line += "  material=" + item["material"].get<std::string>();
        if (item.contains("parent") && item["parent"].is_string())
            line += "  parent=" + item["parent"].get<std::string>();
        if (!item.value("visible", true)) line += "  hidden";
    } else if (collection == "groups") {
        if (item.contains("parent") && item["parent"].is_string())
            line += "  parent=" + item["parent"].get<std::string>();
        const Json children = item.value("children", Json::object());
        line += "  groups=" + std::to_string(children.value("groups", uint64_t(0))) +
                "  instances=" + std::to_string(children.value("instances", uint64_t(0)));
        if (!item.value("visible", true)) line += "  hidden";
    } else if (collection == "meshes") {
        line += "  vertices=" + std::to_string(item.value("vertices", uint64_t(0))) +
                "  triangles=" + std::to_string(item.value("triangles", uint64_t(0))) +
                "  instances=" + std::to_string(item.value("instances", uint64_t(0)));
    } else if (collection == "lights") {
        line += "  type=" + item.value("type", std::string("?"));
    } else if (collection == "textures") {
        line += "  " + std::to_string(item.value("width", uint64_t(0))) + "x" +
                std::to_string(item.value("height", uint64_t(0))) + "  " +
                item.value("format", std::string("?"));
    }
    return line;
}

}  // namespace

const std::vector<std::string>& scene_collections() {
    static const std::vector<std::string> names = {"meshes", "instances", "materials", "groups",
                                                   "lights", "textures"};
    return names;
}

int run_scene_list(Transport& t, const Console& c, const SceneListArgs& args) {
    std::multimap<std::string, std::string> query;
    query.emplace("limit", std::to_string(args.page_size));
    if (args.mesh) query.emplace("mesh", *args.mesh);
    if (args.visible) query.emplace("visible", *args.visible ? "true" : "false");
    if (args.parent) query.emplace("parent", *args.parent);
    const std::string what = "listing " + args.collection;
    uint64_t printed = 0;
    std::optional<uint64_t> first_version;
    while (true) {
        int code = OK;
        const auto page = json_answer(c, t, what, t.scene_list(args.collection, query), code);
        if (!page) return code;
        const uint64_t version = page->value("version", uint64_t(0));
        if (!first_version) first_version = version;
        const Json items = page->value("items", Json::array());
        for (const Json& item : items) {
            if (args.max_items && printed == *args.max_items) return OK;
            c.out << (c.json ? item.dump() : item_line(args.collection, item)) << '\n';
            ++printed;
        }
        const Json next = page->value("next_cursor", Json(nullptr));
        if (!next.is_string()) break;
        query.erase("cursor");
        query.emplace("cursor", next.get<std::string>());
    }
    if (!c.json)
        c.err << printed << " " << args.collection << " at version " << *first_version << '\n';
    return OK;
}

int run_scene_get(Transport& t, const Console& c, const std::string& kind, const std::string& id) {
    static const std::pair<const char*, const char*> KINDS[] = {{"mesh", "meshes"},
                                                                {"instance", "instances"},
                                                                {"material", "materials"},
                                                                {"group", "groups"},
                                                                {"light", "lights"},
                                                                {"texture", "textures"}};
    for (const auto& [singular, collection] : KINDS) {
        if (kind != singular) continue;
        int code = OK;
        const auto doc = json_answer(c, t, "getting " + kind + " '" + id + "'",
                                     t.scene_object(collection, id), code);
        if (!doc) return code;
        c.out << (c.json ? doc->dump() : doc->dump(2)) << '\n';
        return OK;
    }
    c.err << "strata: unknown object kind '" << kind << "': mesh, instance, material or group\n";
    return BAD_INPUT;
}

namespace {

/// The outline of one tree level, two spaces per depth.
void print_tree(const Console& c, const Json& node, int indent) {
    const std::string pad(std::size_t(indent) * 2, ' ');
    for (const Json& g : node.value("groups", Json::array())) {
        c.out << pad << g.value("id", std::string("?")) << "/  (" << g.value("group_count", 0)
              << " groups, " << g.value("instance_count", 0) << " instances"
              << (g.value("world_visible", true) ? "" : ", hidden") << ")\n";
        print_tree(c, g, indent + 1);
    }
    for (const Json& i : node.value("instances", Json::array()))
        c.out << pad << i.value("id", std::string("?"))
              << "  mesh=" << i.value("mesh", std::string("?"))
              << (i.value("world_visible", true) ? "" : "  hidden") << '\n';
}

}  // namespace

int run_scene_tree(Transport& t, const Console& c, const SceneTreeArgs& args) {
    std::multimap<std::string, std::string> query;
    query.emplace("depth", std::to_string(args.depth));
    query.emplace("max_nodes", std::to_string(args.max_nodes));
    if (args.group) query.emplace("group", *args.group);
    int code = OK;
    // The tree lives at /v1/scene/tree, beside the collections.
    const auto doc = json_answer(c, t, "reading the tree", t.scene_list("tree", query), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    print_tree(c, *doc, 0);
    if (doc->value("truncated", false))
        c.err << "(cut at " << args.max_nodes << " nodes; raise --max-nodes or use --group)\n";
    return OK;
}

int run_pick(Transport& t, const Console& c, const PickArgs& args) {
    Json body = {{"width", args.width},
                 {"height", args.height},
                 {"pixels", Json::array({Json::array({args.x, args.y})})}};
    int code = OK;
    const auto doc = json_answer(c, t, "pick", t.pick(body.dump()), code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
        return OK;
    }
    const Json hits = doc->value("hits", Json::array());
    const Json hit = hits.empty() ? Json(nullptr) : hits[0];
    if (!hit.is_object()) {
        c.out << "nothing at (" << args.x << ", " << args.y << ") at version "
              << doc->value("version", uint64_t(0)) << '\n';
        return OK;
    }
    c.out << "instance " << hit.value("instance", std::string("?")) << "  mesh "
          << hit.value("mesh", std::string("?"));
    const Json path = hit.value("group_path", Json::array());
    if (!path.empty()) {
        std::string joined;
        for (const Json& g : path) joined += (joined.empty() ? "" : "/") + g.get<std::string>();
        c.out << "  groups " << joined;
    }
    c.out << "  primitive " << hit.value("primitive", uint64_t(0)) << "  distance "
          << hit.value("distance", 0.0) << "  user_id " << hit.value("user_id", uint64_t(0))
          << "  at version " << doc->value("version", uint64_t(0)) << '\n';
    return OK;
}

}  // namespace strata::cli

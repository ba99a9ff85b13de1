// `strata scene`, `strata scene list`, `strata scene get`, `strata scene tree` and `strata pick`:
// reading the scene as a summary, object by object or as an outline, and asking what lies under a
// pixel.

#include "clients/cli/commands.h"

#include <cstdio>
#include <iterator>
#include <ostream>

namespace strata::cli {

namespace {

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
        // A deforming mesh (vertex keys for deformation blur) says how many keys it has.
        if (const uint64_t keys = item.value("motion_keys", uint64_t(1)); keys > 1)
            line += "  keys=" + std::to_string(keys);
    } else if (collection == "lights") {
        line += "  type=" + item.value("type", std::string("?"));
    } else if (collection == "textures") {
        line += "  " + std::to_string(item.value("width", uint64_t(0))) + "x" +
                std::to_string(item.value("height", uint64_t(0))) + "  " +
                item.value("format", std::string("?"));
    }
    return line;
}

/// "0,4.5,11" for a JSON array of numbers: the way --eye and --target take them.
std::string numbers(const Json& list) {
    std::string out;
    for (const Json& v : list) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%g", v.is_number() ? v.get<double>() : 0.0);
        out += (out.empty() ? "" : ",") + std::string(buf);
    }
    return out.empty() ? "?" : out;
}

/// A size for people: "812 bytes", "4.4 KiB", "4.8 MiB".
std::string size_text(uint64_t bytes) {
    if (bytes < 1024) return std::to_string(bytes) + " bytes";
    static const char* const UNITS[] = {"KiB", "MiB", "GiB", "TiB"};
    double value = double(bytes) / 1024;
    std::size_t unit = 0;
    for (; value >= 1024 && unit + 1 < std::size(UNITS); ++unit) value /= 1024;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f %s", value, UNITS[unit]);
    return buf;
}

/// `strata scene` for people: one "label  value" line per fact, from GET /v1/scene and the
/// memory and last report of GET /v1/stats.
std::string scene_summary(const Json& scene, const Json& stats) {
    std::string out;
    auto line = [&out](const std::string& label, const std::string& value) {
        out += label + std::string(label.size() < 11 ? 11 - label.size() : 1, ' ') + value + '\n';
    };
    const Json counts = scene.value("counts", Json::object());
    auto count = [&counts](const std::string& name) {
        return std::to_string(counts.value(name, uint64_t(0)));
    };
    line("version", std::to_string(scene.value("version", uint64_t(0))));
    for (const std::string& collection : scene_collections()) line(collection, count(collection));
    line("triangles", count("triangles") + " in meshes, " + count("instanced_triangles") +
                          " in visible instances");
    const Json memory = stats.value("memory_bytes", Json::object());
    line("memory", "blas " + size_text(memory.value("blas", uint64_t(0))) + ", tlas " +
                       size_text(memory.value("tlas", uint64_t(0))));
    const Json camera = scene.value("camera", Json::object());
    line("camera", "eye " + numbers(camera.value("eye", Json::array())) + "  target " +
                       numbers(camera.value("target", Json::array())) + "  fov " +
                       numbers(Json::array({camera.value("fov_y_deg", 0.0)})));
    const Json last = stats.value("last_report", Json());
    line("last", last.is_object() ? report_summary(last) : "no commit yet");
    return out;
}

}  // namespace

int run_scene(Transport& t, const Console& c) {
    int code = OK;
    const auto scene = json_answer(c, t, "scene", t.scene(), code);
    if (!scene) return code;
    if (c.json) {
        c.out << scene->dump() << '\n';
        return OK;
    }
    const auto stats = json_answer(c, t, "stats", t.stats(), code);
    if (!stats) return code;
    c.out << scene_summary(*scene, *stats);
    return OK;
}

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
    c.err << "strata: unknown object kind '" << kind
          << "': mesh, instance, material, group, light or texture\n";
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
    const Json camera = camera_json(args.camera);
    if (!camera.empty()) body["camera"] = camera;
    if (args.time) body["time"] = *args.time;
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

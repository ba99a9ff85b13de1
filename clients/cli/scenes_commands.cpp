// `strata scenes`, `strata scenes create` and `strata scenes delete`: the server's named scenes
// (protocol/README.md, "Named scenes").

#include <string>

#include "clients/cli/commands.h"
#include "clients/cli/outcome.h"

namespace strata::cli {

namespace {

/// "city  v12  3 meshes  1000 instances  1.2M triangles  durable"
std::string scene_line(const Json& s) {
    std::string line = s.value("name", std::string("?")) + "  v" +
                       std::to_string(s.value("version", uint64_t(0))) + "  " +
                       std::to_string(s.value("meshes", uint64_t(0))) + " meshes  " +
                       std::to_string(s.value("instances", uint64_t(0))) + " instances  " +
                       std::to_string(s.value("triangles", uint64_t(0))) + " triangles";
    if (s.value("durable", false)) line += "  durable";
    return line;
}

}  // namespace

int run_scenes(Transport& t, const Console& c) {
    int code = OK;
    const auto doc = json_answer(c, t, "scenes", t.scenes(), code);
    if (!doc) return code;
    for (const Json& s : doc->value("scenes", Json::array()))
        c.out << (c.json ? s.dump() : scene_line(s)) << '\n';
    return OK;
}

int run_scene_create(Transport& t, const Console& c, const SceneCreateArgs& args) {
    Json budget = Json::object();
    if (args.max_triangles) budget["max_triangles"] = *args.max_triangles;
    if (args.max_vertices) budget["max_vertices"] = *args.max_vertices;
    if (args.max_instances) budget["max_instances"] = *args.max_instances;
    if (args.max_texture_mb) budget["max_texture_mb"] = *args.max_texture_mb;
    const Reply reply =
        t.put_scene(args.name, budget.empty() ? "" : Json{{"budget", budget}}.dump());
    int code = OK;
    const auto doc = json_answer(c, t, "scenes create", reply, code);
    if (!doc) return code;
    if (c.json) {
        c.out << doc->dump() << '\n';
    } else {
        c.out << (reply.status == 201 ? "created " : "exists  ") << scene_line(*doc) << '\n';
    }
    return OK;
}

int run_scene_delete(Transport& t, const Console& c, const std::string& name) {
    const Reply reply = t.delete_scene(name);
    if (!reply.ok()) return refused(c, t, "scenes delete", reply);
    if (!c.json) c.out << "deleted " << name << '\n';
    return OK;
}

}  // namespace strata::cli

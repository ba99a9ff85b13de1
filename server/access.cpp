// Access per scene: the role each request needs (access.h).

#include "server/access.h"

#include "server/request_target.h"
#include "server/scene_path.h"

namespace strata::server {

namespace {

/// The role a request on one of a scene's routes needs: reading for GET and for the POSTs that
/// only read (renders, picks), editing for every other POST.
Role route_role(std::string_view method, std::string_view route) {
    if (method == "GET" || method == "HEAD") return Role::Read;
    if (method == "POST" && (route == "/v1/render" || route == "/v1/pick")) return Role::Read;
    return Role::Edit;
}

}  // namespace

Access required_access(std::string_view method, std::string_view path) {
    if (const std::optional<ScenePath> scoped = scene_path(path))
        return {decode_path_segment(scoped->scene), route_role(method, scoped->route)};
    if (path == "/v1/scenes" || path == "/v1/openapi.json") return {};
    if (path.substr(0, SCENES_PREFIX.size()) == SCENES_PREFIX) {
        const std::string name = decode_path_segment(path.substr(SCENES_PREFIX.size()));
        const bool reads = method == "GET" || method == "HEAD";
        return {name, reads ? Role::Read : Role::Admin};
    }
    return {"default", route_role(method, path)};
}

std::optional<protocol::Problem> refuse_access(const Grants& grants, const Access& need) {
    if (need.scene.empty()) return std::nullopt;
    const Role has = grants.in(need.scene);
    if (has >= need.role) return std::nullopt;
    // A scene this token cannot see is answered as one that does not exist, unless the request
    // would make or delete it: then it is 403 either way, and says nothing about the scene.
    if (has == Role::None && need.role != Role::Admin && need.scene != "default") {
        protocol::Problem p = protocol::make_problem(
            protocol::ProblemType::NotFound,
            "no scene named '" + need.scene.substr(0, 80) + "'");
        p.pointer = "/scene";
        return p;
    }
    return protocol::make_problem(
        protocol::ProblemType::Forbidden,
        "this token's role in scene '" + need.scene.substr(0, 80) + "' is " +
            role_name(has) + "; this request needs " + role_name(need.role));
}

}  // namespace strata::server

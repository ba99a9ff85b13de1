#pragma once
// Paths under a named scene: /v1/scenes/NAME/REST is the route /v1/REST of scene NAME
// (named_scenes.h). The front end asks this to treat such a request as it treats /v1/REST
// (renders are heavy, the stream takes ?access_token=); the application to dispatch it.

#include <optional>
#include <string>
#include <string_view>

namespace strata::server {

inline constexpr std::string_view SCENES_PREFIX = "/v1/scenes/";

struct ScenePath {
    std::string_view scene;  ///< NAME, still percent-encoded as the target had it
    std::string route;       ///< "/v1/REST"
};

/// The scene and route of "/v1/scenes/NAME/REST" (REST not empty); nullopt for other paths,
/// /v1/scenes/NAME itself included.
inline std::optional<ScenePath> scene_path(std::string_view path) {
    if (path.substr(0, SCENES_PREFIX.size()) != SCENES_PREFIX) return std::nullopt;
    const std::string_view tail = path.substr(SCENES_PREFIX.size());
    const std::size_t slash = tail.find('/');
    if (slash == 0 || slash == std::string_view::npos || slash + 1 == tail.size())
        return std::nullopt;
    return ScenePath{tail.substr(0, slash), "/v1/" + std::string(tail.substr(slash + 1))};
}

/// The route `path` names, whichever scene it is under: "/v1/scenes/a/render" -> "/v1/render".
inline std::string route_of(std::string_view path) {
    const std::optional<ScenePath> scoped = scene_path(path);
    return scoped ? scoped->route : std::string(path);
}

}  // namespace strata::server

#pragma once
// How the command-line client reaches Strata: over HTTP (HttpTransport), or in-process
// (EmbeddedTransport, `strata play --embedded`). Both answer with the server's own statuses,
// documents and headers, so everything above this interface is the same for both.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace strata::cli {

/// One answer from Strata, or why there was none.
struct Reply {
    int status = 0;     ///< HTTP status; 0: no answer (see `error`)
    std::string error;  ///< why there was no answer (connection refused, timeout, ...)
    std::string content_type;
    std::string body;
    std::vector<std::pair<std::string, std::string>> headers;

    /// A header's value, matched case-insensitively ("" when absent).
    std::string header(std::string_view name) const;
    /// True for a 2xx answer.
    bool ok() const { return status >= 200 && status < 300; }
};

/// The scene version an answer's ETag names ("N" or N), if it has one.
std::optional<uint64_t> etag_version(const Reply& reply);

/// `text` with every byte but RFC 3986's unreserved characters percent-encoded: a path segment
/// or query value that arrives as written.
std::string percent_encode(std::string_view text);

/// A failed answer for people: a problem document as its status, title, detail, edit index,
/// pointer and type, one per line; any other answer as its status and the start of its body; no
/// answer as why. Never raw JSON.
std::string describe_failure(const Reply& reply);

/// The protocol's endpoints, whatever carries them (protocol/README.md).
class Transport {
public:
    virtual ~Transport() = default;

    /// POST /v1/edits with `body` ({"edits": [...]}), conditional on `if_match` when given.
    virtual Reply edits(std::string body, const std::optional<std::string>& if_match) = 0;
    /// POST /v1/undo (POST /v1/redo when `redo`), conditional on `if_match` when given.
    virtual Reply undo(bool redo, const std::optional<std::string>& if_match) = 0;
    /// GET /v1/history with `query` (limit, cursor).
    virtual Reply history(const std::multimap<std::string, std::string>& query) = 0;
    /// POST /v1/commit.
    virtual Reply commit() = 0;
    /// GET /v1/plan.
    virtual Reply plan() = 0;
    /// POST /v1/render with a JSON request body.
    virtual Reply render(const std::string& body) = 0;
    /// GET /v1/stats.
    virtual Reply stats() = 0;
    /// GET /v1/scene.
    virtual Reply scene() = 0;
    /// GET /v1/scene/{collection} (meshes, instances, materials or groups): one page of the
    /// listing; "tree" is GET /v1/scene/tree.
    virtual Reply scene_list(const std::string& collection,
                             const std::multimap<std::string, std::string>& query) = 0;
    /// GET /v1/scene/{collection}/{id}.
    virtual Reply scene_object(const std::string& collection, const std::string& id) = 0;
    /// POST /v1/pick with a JSON request body.
    virtual Reply pick(const std::string& body) = 0;
    /// GET /v1/scene/snapshot: the scene as a snapshot file.
    /// `at_version`, or `at_time` (RFC 3339): the scene as it was then (from the server's data
    /// directory).
    virtual Reply get_snapshot(std::optional<uint64_t> at_version,
                               const std::optional<std::string>& at_time) = 0;
    /// POST /v1/scene/snapshot: replaces the scene with a snapshot file's.
    virtual Reply put_snapshot(std::string bytes) = 0;
    /// POST /v1/assets: imports a model file's bytes; `query` holds name, format, prefix,
    /// instance.
    virtual Reply import_asset(std::string bytes,
                               const std::multimap<std::string, std::string>& query) = 0;
    /// GET /v1/assets, or GET /v1/assets/{id} when `id` is given.
    virtual Reply assets(const std::optional<std::string>& id) = 0;
    /// DELETE /v1/assets/{id}.
    virtual Reply delete_asset(const std::string& id) = 0;
    /// PUT /v1/assets/{id}: re-imports a model file's bytes as asset `id`; `query` as for
    /// import_asset without prefix.
    virtual Reply put_asset(const std::string& id, std::string bytes,
                            const std::multimap<std::string, std::string>& query) = 0;
    /// GET /v1/scenes; PUT and DELETE /v1/scenes/{name} (the directory of named scenes). Only a
    /// server has one: other transports answer that they hold a single scene.
    virtual Reply scenes();
    virtual Reply put_scene(const std::string& name, const std::string& body);
    virtual Reply delete_scene(const std::string& name);
    /// Where requests go, for messages: "http://127.0.0.1:7070" or "the embedded engine".
    virtual std::string describe() const = 0;
};

}  // namespace strata::cli

// POST /v1/assets: the upload through an importer (protocol/assets/) into one engine batch.

#include <algorithm>

#include "protocol/api.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/import.h"
#include "protocol/safe_text.h"

namespace strata::protocol {

namespace {

using assets::AssetError;
using assets::AssetFormat;

/// Longest prefix: ids must stay under MAX_ID_LENGTH with ".material12345.3" appended.
constexpr std::size_t MAX_PREFIX = 200;

Problem bad_query(const std::string& param, const std::string& why) {
    Problem p = make_problem(ProblemType::InvalidRequest, param + ": " + why);
    p.pointer = "/" + param;
    return p;
}

Problem asset_problem(const AssetError& e) {
    Problem p = make_problem(
        e.kind == AssetError::Kind::TooLarge ? ProblemType::TooLarge : ProblemType::InvalidAsset,
        e.describe());
    p.file = e.file;
    if (!e.element.empty()) p.element = e.element;
    return p;
}

/// A default prefix from a file name: its stem, with characters outside [A-Za-z0-9_-] as '_'.
std::string prefix_from_name(std::string_view name) {
    name = name.substr(name.find_last_of("/\\") == std::string_view::npos
                           ? 0
                           : name.find_last_of("/\\") + 1);
    if (const auto dot = name.rfind('.'); dot != std::string_view::npos && dot > 0)
        name = name.substr(0, dot);
    std::string out;
    for (char c : name.substr(0, 64))
        out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
    return out;
}

bool has_control(std::string_view s) {
    return std::any_of(s.begin(), s.end(), [](char c) {
        return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
    });
}

struct AssetQuery {
    AssetFormat format = AssetFormat::Glb;
    std::string name;
    std::string prefix;
    std::optional<std::string> parent;
    bool instance = true;
};

std::optional<AssetQuery> parse_query(const std::multimap<std::string, std::string>& query,
                                      std::optional<std::string_view> content_type,
                                      Problem& problem) {
    for (const auto& [key, value] : query) {
        if (key != "format" && key != "name" && key != "prefix" && key != "instance" &&
            key != "parent") {
            problem = bad_query(
                key, "unknown parameter (expected format, name, prefix, parent, instance)");
            return std::nullopt;
        }
        if (query.count(key) > 1) {
            problem = bad_query(key, "given more than once");
            return std::nullopt;
        }
    }
    auto get = [&](const char* key) -> std::optional<std::string> {
        const auto it = query.find(key);
        return it == query.end() ? std::nullopt : std::optional(it->second);
    };
    AssetQuery q;
    // Step 1: the format: ?format= wins, then the Content-Type, then the name's extension.
    std::optional<AssetFormat> format;
    if (auto f = get("format")) {
        format = assets::format_from_name(*f);
        if (!format) {
            problem = bad_query("format", "'" + to_valid_utf8(*f) +
                                              "' is not one of glb, gltf, obj, ply");
            return std::nullopt;
        }
    }
    if (!format && content_type) format = assets::format_from_media_type(*content_type);
    q.name = get("name").value_or("");
    if (!is_valid_utf8(q.name) || has_control(q.name) || q.name.size() > 256) {
        problem = bad_query("name", "must be valid UTF-8 without control characters, at most "
                                    "256 bytes");
        return std::nullopt;
    }
    if (!format && q.name.find('.') != std::string::npos)
        format = assets::format_from_name(q.name.substr(q.name.rfind('.') + 1));
    if (!format) {
        problem = make_problem(
            ProblemType::InvalidRequest,
            "the file's format is unknown: give ?format=glb|gltf|obj|ply, or a Content-Type of "
            "model/gltf-binary, model/gltf+json, model/obj or application/ply");
        return std::nullopt;
    }
    q.format = *format;
    if (q.name.empty()) q.name = std::string("upload.") + assets::format_name(q.format);
    // Step 2: the id prefix and the instance flag.
    q.prefix = get("prefix").value_or(prefix_from_name(q.name));
    if (q.prefix.empty()) q.prefix = assets::format_name(q.format);
    if (q.prefix.size() > MAX_PREFIX || !is_valid_utf8(q.prefix) || has_control(q.prefix)) {
        problem = bad_query("prefix", "must be 1 to " + std::to_string(MAX_PREFIX) +
                                          " bytes of UTF-8 without control characters");
        return std::nullopt;
    }
    if (auto parent = get("parent")) {
        if (parent->empty() || parent->size() > 256 || !is_valid_utf8(*parent) ||
            has_control(*parent)) {
            problem = bad_query("parent", "must be a group id");
            return std::nullopt;
        }
        q.parent = *parent;
    }
    if (auto inst = get("instance")) {
        if (*inst != "true" && *inst != "false") {
            problem = bad_query("instance", "expected true or false");
            return std::nullopt;
        }
        q.instance = *inst == "true";
    }
    return q;
}

}  // namespace

ApiResponse post_assets(Engine& engine, std::string body,
                        const std::multimap<std::string, std::string>& query,
                        std::optional<std::string_view> content_type,
                        std::optional<std::string_view> if_match, const ApiLimits& api_limits,
                        const BatchApply* apply) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return problem_response(problem);
    const auto q = parse_query(query, content_type, problem);
    if (!q) return problem_response(problem);

    // Step 1: the room left in the scene budget bounds what the importer may allocate (the
    // engine checks the batch against the budget again when it applies it).
    assets::ImportLimits limits;
    engine.read([&](const Scene& s) {
        const SceneBudget& b = api_limits.budget;
        const MeshTotals& t = s.mesh_totals();
        limits.max_vertices = b.max_vertices > t.vertices ? b.max_vertices - t.vertices : 0;
        limits.max_triangles = b.max_triangles > t.triangles ? b.max_triangles - t.triangles : 0;
    });

    // Step 2: import, then build the one batch.
    auto asset = assets::import_asset(
        q->format, std::span(reinterpret_cast<const uint8_t*>(body.data()), body.size()), q->name,
        limits);
    body = {};
    if (!asset) return problem_response(asset_problem(asset.error()));
    assets::AssetBatch out =
        assets::asset_to_batch(std::move(asset.value()), {q->prefix, q->instance, q->parent});
    const std::size_t edits = out.batch.edits.size();

    // Step 3: apply it like any batch; an engine refusal names the id it was creating.
    auto applied = apply ? (*apply)(std::move(out.batch), condition->version)
                         : engine.apply(std::move(out.batch), condition->version);
    if (!applied) {
        const Error& e = applied.error();
        if (e.code == ErrorCode::VersionMismatch) {
            const uint64_t version = engine.read([](const Scene& s) { return s.version(); });
            return with_etag(problem_response(make_problem(ProblemType::VersionMismatch,
                                                           "If-Match: " + e.message)),
                             version);
        }
        Error plain = e;
        plain.field.clear();
        plain.edit_index = Error::NO_INDEX;
        if (e.edit_index < out.edit_ids.size())
            plain.message = q->name + ": creating '" + out.edit_ids[e.edit_index] +
                            "': " + e.message +
                            (e.code == ErrorCode::DuplicateId ? " (choose another ?prefix=)" : "");
        else
            plain.message = q->name + ": " + e.message;
        Problem p = problem_from(plain);
        p.file = q->name;
        return problem_response(p);
    }
    const ApplyResult& done = applied.value();
    const Json answer = {{"version", done.version},  {"applied", edits},
                         {"format", assets::format_name(q->format)},
                         {"textures", out.textures}, {"meshes", out.meshes},
                         {"materials", out.materials},
                         {"groups", out.groups},     {"instances", out.instances},
                         {"warnings", out.warnings}};
    return with_etag(json_response(200, answer), done.version);
}

}  // namespace strata::protocol

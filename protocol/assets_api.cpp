// POST /v1/assets: the upload through an importer (protocol/assets/) into one engine batch.

#include <algorithm>
#include <cctype>

#include "protocol/api.h"
#include "protocol/assets/archive_import.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/import.h"
#include "protocol/framing.h"
#include "protocol/safe_text.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

namespace {

using assets::AssetFormat;

/// Longest prefix: ids must stay under MAX_ID_LENGTH with ".material12345.3" appended.
constexpr std::size_t MAX_PREFIX = 200;

Problem bad_query(const std::string& param, const std::string& why) {
    Problem p = make_problem(ProblemType::InvalidRequest, param + ": " + why);
    p.pointer = "/" + param;
    return p;
}

/// A default prefix from a file name: its stem, with characters outside [A-Za-z0-9_-] as '_'.
std::string prefix_from_name(std::string_view name) {
    name = name.substr(
        name.find_last_of("/\\") == std::string_view::npos ? 0 : name.find_last_of("/\\") + 1);
    if (const auto dot = name.rfind('.'); dot != std::string_view::npos && dot > 0)
        name = name.substr(0, dot);
    std::string out;
    for (char c : name.substr(0, 64))
        out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
    return out;
}

bool has_control(std::string_view s) {
    return std::any_of(s.begin(), s.end(),
                       [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

/// A tar archive by its Content-Type (parameters after ';' ignored).
bool is_tar_media_type(std::string_view type) {
    std::string t = lower(type.substr(0, type.find(';')));
    while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.pop_back();
    return t == "application/x-tar" || t == "application/tar";
}

bool ends_with_tar(std::string_view name) {
    return name.size() >= 4 && lower(name.substr(name.size() - 4)) == ".tar";
}

struct AssetQuery {
    AssetFormat format = AssetFormat::Glb;
    bool archive = false;  ///< a tar of one model and its side files; `format` is then the model's
    std::string name;
    std::string prefix;
    std::optional<std::string> parent;
    bool instance = true;
};

using Query = std::multimap<std::string, std::string>;

std::optional<std::string> value_of(const Query& query, const char* key) {
    const auto it = query.find(key);
    return it == query.end() ? std::nullopt : std::optional(it->second);
}

/// Each parameter known and given at most once.
bool check_keys(const Query& query, Problem& problem) {
    for (const auto& [key, value] : query) {
        if (key != "format" && key != "name" && key != "prefix" && key != "instance" &&
            key != "parent") {
            problem = bad_query(
                key, "unknown parameter (expected format, name, prefix, parent, instance)");
            return false;
        }
        if (query.count(key) > 1) {
            problem = bad_query(key, "given more than once");
            return false;
        }
    }
    return true;
}

/// Step 1: the format: ?format= wins, then the Content-Type, then the name's extension. A tar
/// archive (?format=tar, application/x-tar, a name ending in .tar) holds the model and its side
/// files; the model's format then comes from its extension inside the archive.
bool parse_format(const Query& query, std::optional<std::string_view> content_type, AssetQuery& q,
                  Problem& problem) {
    std::optional<AssetFormat> format;
    if (auto f = value_of(query, "format")) {
        q.archive = lower(*f) == "tar";
        format = assets::format_from_name(*f);
        if (!format && !q.archive) {
            problem = bad_query(
                "format", "'" + to_valid_utf8(*f) + "' is not one of glb, gltf, obj, ply, tar");
            return false;
        }
    }
    if (!format && !q.archive && content_type) {
        format = assets::format_from_media_type(*content_type);
        q.archive = !format && is_tar_media_type(*content_type);
    }
    q.name = value_of(query, "name").value_or("");
    if (!is_valid_utf8(q.name) || has_control(q.name) || q.name.size() > 256) {
        problem = bad_query("name",
                            "must be valid UTF-8 without control characters, at most "
                            "256 bytes");
        return false;
    }
    if (!format && !q.archive && q.name.find('.') != std::string::npos) {
        format = assets::format_from_name(q.name.substr(q.name.rfind('.') + 1));
        q.archive = !format && ends_with_tar(q.name);
    }
    if (!format && !q.archive) {
        problem = make_problem(
            ProblemType::InvalidRequest,
            "the file's format is unknown: give ?format=glb|gltf|obj|ply|tar, or a Content-Type "
            "of model/gltf-binary, model/gltf+json, model/obj, application/ply or "
            "application/x-tar");
        return false;
    }
    if (format) q.format = *format;
    if (q.name.empty())
        q.name = q.archive ? "upload.tar" : std::string("upload.") + assets::format_name(q.format);
    return true;
}

/// Step 2: the id prefix (an archive's default is its model's stem, set once it is found), the
/// parent group and the instance flag.
bool parse_placement(const Query& query, AssetQuery& q, Problem& problem) {
    const std::optional<std::string> prefix = value_of(query, "prefix");
    q.prefix = prefix.value_or(q.archive ? "" : prefix_from_name(q.name));
    if (q.prefix.empty() && !q.archive) q.prefix = assets::format_name(q.format);
    if (q.prefix.size() > MAX_PREFIX || !is_valid_utf8(q.prefix) || has_control(q.prefix) ||
        (q.prefix.empty() && prefix)) {
        problem = bad_query("prefix", "must be 1 to " + std::to_string(MAX_PREFIX) +
                                          " bytes of UTF-8 without control characters");
        return false;
    }
    if (auto parent = value_of(query, "parent")) {
        if (parent->empty() || parent->size() > 256 || !is_valid_utf8(*parent) ||
            has_control(*parent)) {
            problem = bad_query("parent", "must be a group id");
            return false;
        }
        q.parent = *parent;
    }
    if (auto inst = value_of(query, "instance")) {
        if (*inst != "true" && *inst != "false") {
            problem = bad_query("instance", "expected true or false");
            return false;
        }
        q.instance = *inst == "true";
    }
    return true;
}

std::optional<AssetQuery> parse_query(const Query& query,
                                      std::optional<std::string_view> content_type,
                                      Problem& problem) {
    AssetQuery q;
    if (!check_keys(query, problem) || !parse_format(query, content_type, q, problem) ||
        !parse_placement(query, q, problem))
        return std::nullopt;
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
    auto q = parse_query(query, content_type, problem);
    if (!q) return problem_response(problem);

    // Step 1: the room left in the scene budget bounds what the importer may allocate (the
    // engine checks the batch against the budget again when it applies it).
    assets::ImportLimits limits;
    engine.read([&](const Scene& s) {
        const SceneBudget& b = api_limits.budget;
        const MeshTotals& t = s.mesh_totals();
        limits.max_vertices = b.max_vertices > t.vertices ? b.max_vertices - t.vertices : 0;
        const uint64_t used = t.budget_triangles();
        limits.max_triangles = b.max_triangles > used ? b.max_triangles - used : 0;
    });

    // Step 2: import (an archive: its one model with the archive's other files as side files),
    // then build the one batch.
    const std::span bytes(reinterpret_cast<const uint8_t*>(body.data()), body.size());
    std::optional<std::string> model;
    assets::Imported<assets::Asset> asset = assets::Asset{};
    if (q->archive) {
        auto archived = assets::import_archive(bytes, q->name, limits);
        if (archived) {
            q->format = archived.value().format;
            model = archived.value().model;
            if (q->prefix.empty()) q->prefix = prefix_from_name(*model);
            if (q->prefix.empty()) q->prefix = assets::format_name(q->format);
            asset = std::move(archived.value().asset);
        } else {
            asset = Unexpected(archived.error());
        }
    } else {
        asset = assets::import_asset(q->format, bytes, q->name, limits);
    }
    body = {};
    if (!asset) return problem_response(asset.error());
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
    // Where the model landed: the world bounds of the instances it created, to aim at.
    const Bounds3 bounds = engine.read([&](const Scene& s) {
        InstanceBounds world(s);
        Bounds3 box;
        for (const std::string& id : out.instances) {
            const auto i = s.instance(s.find_instance(id));
            if (i) box.extend(world(*i.value()));  // else removed by a batch that landed since
        }
        return box;
    });
    Json answer = {{"version", done.version},
                   {"applied", edits},
                   {"format", assets::format_name(q->format)},
                   {"textures", out.textures},
                   {"meshes", out.meshes},
                   {"materials", out.materials},
                   {"groups", out.groups},
                   {"instances", out.instances},
                   {"bounds", bounds_to_json(bounds)},
                   {"warnings", out.warnings}};
    if (model) answer["model"] = *model;
    return with_etag(json_response(200, answer), done.version);
}

}  // namespace strata::protocol

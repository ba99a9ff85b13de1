// /v1/assets: an upload through an importer (protocol/assets/) into one engine batch (POST), and
// imports as units (GET, DELETE and PUT /v1/assets/{id}; protocol/asset_index.h).

#include <algorithm>
#include <cctype>
#include <map>
#include <set>

#include "protocol/api.h"
#include "protocol/asset_index.h"
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

/// The Content-Types the importers know, comma separated.
std::string media_types() {
    std::string out;
    for (const std::string& t : assets::media_type_names()) out += (out.empty() ? "" : ", ") + t;
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

/// Each parameter known and given at most once; `prefix` only when the path does not name the
/// asset (POST).
bool check_keys(const Query& query, bool prefix, Problem& problem) {
    for (const auto& [key, value] : query) {
        if (key != "format" && key != "name" && (key != "prefix" || !prefix) &&
            key != "instance" && key != "parent") {
            problem = bad_query(key, prefix ? "unknown parameter (expected format, name, prefix, "
                                              "parent, instance)"
                                            : "unknown parameter (expected format, name, parent, "
                                              "instance; the path names the asset)");
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
            problem = bad_query("format", "'" + to_valid_utf8(*f) + "' is not one of " +
                                              assets::format_names() + ", tar");
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
            "the file's format is unknown: give ?format= (one of " + assets::format_names() +
                ", tar), a name with one of those extensions, or a Content-Type (one of " +
                media_types() + ", application/x-tar)");
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

/// The query of POST /v1/assets, or of PUT /v1/assets/{id} when `id` is given (the prefix).
std::optional<AssetQuery> parse_query(const Query& query,
                                      std::optional<std::string_view> content_type,
                                      std::optional<std::string_view> id, Problem& problem) {
    AssetQuery q;
    if (!check_keys(query, !id, problem) || !parse_format(query, content_type, q, problem) ||
        !parse_placement(query, q, problem))
        return std::nullopt;
    if (id) q.prefix = *id;
    return q;
}

/// An upload read and turned into its batch, not applied yet.
struct Upload {
    AssetQuery q;
    std::optional<std::string> model;  ///< an archive's model file
    assets::AssetBatch out;
};

/// The room left in the scene budget, plus `freed` (what a re-import removes): what the
/// importer may allocate (the engine checks the batch against the budget again when it applies).
assets::ImportLimits import_limits(const Scene& s, const SceneBudget& b, const MeshTotals& freed) {
    assets::ImportLimits limits;
    const MeshTotals& t = s.mesh_totals();
    const uint64_t vertices = t.vertices - std::min(t.vertices, freed.vertices);
    const uint64_t used = t.budget_triangles() - std::min(t.budget_triangles(), freed.triangles);
    limits.max_vertices = b.max_vertices > vertices ? b.max_vertices - vertices : 0;
    limits.max_triangles = b.max_triangles > used ? b.max_triangles - used : 0;
    return limits;
}

/// Step: import the body in the importers' sandbox (an archive: its one model with the
/// archive's other files as side files), check what comes back as untrusted, then build the one
/// batch.
Parsed<Upload> read_upload(std::string& body, AssetQuery q, const assets::ImportLimits& limits,
                           const assets::SandboxLimits& sandbox) {
    const std::span bytes(reinterpret_cast<const uint8_t*>(body.data()), body.size());
    const bool archive = q.archive;
    const AssetFormat format = q.format;
    const std::string name = q.name;
    auto imported = assets::run_sandboxed(
        [&]() -> assets::Imported<assets::ImportOutcome> {
            if (!archive) {
                auto asset = assets::import_asset(format, bytes, name, limits);
                if (!asset) return Unexpected(asset.error());
                return assets::ImportOutcome{std::move(asset.value()), format, std::nullopt};
            }
            auto archived = assets::import_archive(bytes, name, limits);
            if (!archived) return Unexpected(archived.error());
            assets::ArchiveAsset& a = archived.value();
            return assets::ImportOutcome{std::move(a.asset), a.format, std::move(a.model)};
        },
        q.name, sandbox);
    body = {};
    if (!imported) return Unexpected(imported.error());
    assets::ImportOutcome& o = imported.value();
    const assets::ErrorSink sink(o.model ? q.name + ": " + *o.model : q.name);
    if (auto fits = assets::check_budget(o.asset, limits, sink); !fits)
        return Unexpected(fits.error());
    if (auto valid = assets::validate_asset(o.asset, sink); !valid)
        return Unexpected(valid.error());
    Upload u;
    q.format = o.format;
    u.model = std::move(o.model);
    if (q.prefix.empty() && u.model) q.prefix = prefix_from_name(*u.model);
    if (q.prefix.empty()) q.prefix = assets::format_name(q.format);
    u.out = assets::asset_to_batch(std::move(o.asset), {q.prefix, q.instance, q.parent, q.name});
    u.q = std::move(q);
    return u;
}

/// A history message: `text`, else `fallback` when it is too long.
std::string batch_message(std::string text, const char* fallback) {
    return text.size() <= MAX_BATCH_MESSAGE_BYTES ? text : std::string(fallback);
}

/// The answer to a batch the engine refused: the version it is at for If-Match, else the error
/// rewritten to name the object edit `edit_index` was about (`doing`: "creating", "removing").
ApiResponse refused(Engine& engine, const Error& e, const std::vector<std::string>& edit_ids,
                    const std::string& file, const std::string& what, const char* doing,
                    const std::string& hint) {
    if (e.code == ErrorCode::VersionMismatch) {
        const uint64_t version = engine.read([](const Scene& s) { return s.version(); });
        return with_etag(problem_response(make_problem(ProblemType::VersionMismatch,
                                                       "If-Match: " + e.message)),
                         version);
    }
    Error plain = e;
    plain.field.clear();
    plain.edit_index = Error::NO_INDEX;
    plain.message = what + ": " +
                    (e.edit_index < edit_ids.size()
                         ? std::string(doing) + " '" + edit_ids[e.edit_index] + "': "
                         : std::string()) +
                    e.message + hint;
    Problem p = problem_from(plain);
    if (!file.empty()) p.file = file;
    return problem_response(p);
}

/// World bounds of the instances `ids` (those removed since are skipped).
Bounds3 instances_bounds(Engine& engine, const std::vector<std::string>& ids) {
    return engine.read([&](const Scene& s) {
        InstanceBounds world(s);
        Bounds3 box;
        for (const std::string& id : ids) {
            const auto i = s.instance(s.find_instance(id));
            if (i) box.extend(world(*i.value()));
        }
        return box;
    });
}

/// The answer of an applied import: the ids it created, where they landed, what it warned.
Json import_answer(const Upload& u, const ApplyResult& done, std::size_t edits,
                   const Bounds3& bounds) {
    Json answer = {{"version", done.version},
                   {"applied", edits},
                   {"format", assets::format_name(u.q.format)},
                   {"textures", u.out.textures},
                   {"meshes", u.out.meshes},
                   {"materials", u.out.materials},
                   {"groups", u.out.groups},
                   {"instances", u.out.instances},
                   {"bounds", bounds_to_json(bounds)},
                   {"warnings", u.out.warnings}};
    if (u.model) answer["model"] = *u.model;
    return answer;
}

ApiResponse not_an_asset(std::string_view id, uint64_t version) {
    return with_etag(problem_response(make_problem(
                         ProblemType::NotFound, "no asset with id '" + std::string(id) + "'")),
                     version);
}

/// How often a write without If-Match reads the asset again when another writer landed between
/// its read and its apply.
constexpr int WRITE_ATTEMPTS = 4;

// Step (PUT): what a re-import keeps. A texture, material or mesh the new file makes exactly as
// it is (same id, same content, and what it refers to kept too) is neither removed nor added, so
// the commit rebuilds nothing for it.

bool same_texture(const TextureRecord& old, const AddTexture& e) {
    return old.name == e.name && *old.encoded == e.data;
}

bool same_material(const Scene& s, const MaterialRecord& old, const AddMaterial& e,
                   const std::set<std::string>& kept_textures) {
    if (!(old.material == e.material)) return false;
    for (std::size_t slot = 0; slot < TEXTURE_SLOT_COUNT; ++slot) {
        const auto texture = s.texture(old.textures[slot]);
        const std::optional<std::string> old_texture =
            texture ? std::optional(texture.value()->id) : std::nullopt;
        if (old_texture != e.textures[slot]) return false;
        if (old_texture && kept_textures.count(*old_texture) == 0) return false;
    }
    return true;
}

bool same_attributes(const MeshRecord& old, const AddMesh& e) {
    bool same = true;
    for_each_vertex_attribute(
        [&](auto a) { same = same && decltype(a)::of(old) == decltype(a)::of(e); });
    return same;
}

bool same_mesh(const Scene& s, const MeshRecord& old, const AddMesh& e,
               const std::set<std::string>& kept_materials) {
    const auto material = s.material(old.material);
    const std::optional<std::string> old_material =
        material ? std::optional(material.value()->id) : std::nullopt;
    return old.name == e.name && old.build == e.build && old_material == e.material &&
           (!old_material || kept_materials.count(*old_material) != 0) &&
           old.positions.get() == e.positions && old.triangles.get() == e.triangles &&
           old.kind == e.kind && old.basis == e.basis && old.style == e.style &&
           old.strands == e.strands && same_attributes(old, e);
}

/// What a re-import keeps, by id.
struct Kept {
    std::set<std::string> textures, materials, meshes;
};

/// Adds to `into` the id of each of `handles` whose record `out` adds again as an `Add` for which
/// `same(record, add)` holds.
template <class Add, class H, class Records, class Same>
void keep_same(const std::vector<H>& handles, const Records& records,
               const std::map<std::string_view, const Edit*>& adds, Same&& same,
               std::set<std::string>& into) {
    for (H h : handles) {
        const auto& r = records.at(h);
        const auto it = adds.find(r.id);
        const Add* add = it == adds.end() ? nullptr : std::get_if<Add>(it->second);
        if (add && same(r, *add)) into.insert(r.id);
    }
}

/// Finds what `out` would add exactly as `old` holds it (textures, then the materials that use
/// kept textures, then the meshes that use kept materials).
Kept find_kept(const Scene& s, const AssetContents& old, const assets::AssetBatch& out) {
    Kept kept;
    std::map<std::string_view, const Edit*> adds;
    for (std::size_t i = 0; i < out.batch.edits.size(); ++i)
        adds.emplace(out.edit_ids[i], &out.batch.edits[i]);
    keep_same<AddTexture>(old.textures, s.textures(), adds, same_texture, kept.textures);
    keep_same<AddMaterial>(
        old.materials, s.materials(), adds,
        [&](const MaterialRecord& r, const AddMaterial& e) {
            return same_material(s, r, e, kept.textures);
        },
        kept.materials);
    keep_same<AddMesh>(
        old.meshes, s.meshes(), adds,
        [&](const MeshRecord& r, const AddMesh& e) { return same_mesh(s, r, e, kept.materials); },
        kept.meshes);
    return kept;
}

/// `a` without what `kept` keeps.
AssetContents without_kept(const Scene& s, AssetContents a, const Kept& kept) {
    std::erase_if(a.textures,
                  [&](TextureHandle h) { return kept.textures.count(s.textures().at(h).id); });
    std::erase_if(a.materials,
                  [&](MaterialHandle h) { return kept.materials.count(s.materials().at(h).id); });
    std::erase_if(a.meshes, [&](MeshHandle h) { return kept.meshes.count(s.meshes().at(h).id); });
    return a;
}

/// The ids `a` owns that `out` does not create again.
std::vector<std::string> gone_ids(const Scene& s, const AssetContents& a,
                                  const assets::AssetBatch& out) {
    const std::set<std::string_view> made(out.edit_ids.begin(), out.edit_ids.end());
    std::vector<std::string> gone;
    const auto check = [&](const std::string& id) {
        if (made.count(id) == 0) gone.push_back(id);
    };
    for (TextureHandle h : a.textures) check(s.textures().at(h).id);
    for (MaterialHandle h : a.materials) check(s.materials().at(h).id);
    for (MeshHandle h : a.meshes) check(s.meshes().at(h).id);
    for (GroupHandle h : a.groups) check(s.groups().at(h).id);
    for (InstanceHandle h : a.instances) check(s.instances().at(h).id);
    return gone;
}

/// The batch of a re-import read at one version: the old asset's removal (less what is kept),
/// then the new one's edits (less what is kept), the asset's group placed where the old one was
/// unless the query names a parent.
struct Replacement {
    uint64_t version = 0;
    bool replaced = false;  ///< false: no asset had the id (a first import)
    EditBatch batch;
    std::vector<std::string> edit_ids;
    std::size_t removals = 0;  ///< the batch's first edits, which remove the old asset
    Kept kept;
    std::vector<std::string> gone;
};

Replacement plan_replacement(const Scene& s, const Upload& u) {
    Replacement r;
    r.version = s.version();
    const std::optional<AssetContents> old = find_asset(s, u.q.prefix);
    std::optional<AddGroup> placement;
    if (old) {
        r.replaced = true;
        r.kept = find_kept(s, *old, u.out);
        r.gone = gone_ids(s, *old, u.out);
        r.batch.edits = removal_edits(s, without_kept(s, *old, r.kept), r.edit_ids);
        r.removals = r.batch.edits.size();
        const GroupRecord& g = s.groups().at(old->group);
        placement = AddGroup{};
        placement->transform = g.transform;
        placement->visible = g.visible;
        placement->name = g.name;
        if (!u.q.parent) {
            const auto parent = s.group(g.parent);
            if (parent) placement->parent = parent.value()->id;
        }
    }
    const std::set<std::string> kept_ids = [&] {
        std::set<std::string> all(r.kept.textures);
        all.insert(r.kept.materials.begin(), r.kept.materials.end());
        all.insert(r.kept.meshes.begin(), r.kept.meshes.end());
        return all;
    }();
    for (std::size_t i = 0; i < u.out.batch.edits.size(); ++i) {
        const std::string& id = u.out.edit_ids[i];
        if (i != u.out.root_edit && kept_ids.count(id) != 0) continue;
        Edit e = u.out.batch.edits[i];
        if (i == u.out.root_edit && placement) {
            AddGroup& g = std::get<AddGroup>(e);
            g.transform = placement->transform;
            g.visible = placement->visible;
            g.name = placement->name;
            if (!u.q.parent) g.parent = placement->parent;
        }
        r.batch.edits.push_back(std::move(e));
        r.edit_ids.push_back(id);
    }
    r.batch.info.message = batch_message(
        (r.replaced ? "re-import asset '" : "import asset '") + u.q.prefix + "' from " + u.q.name,
        r.replaced ? "re-import asset" : "import asset");
    return r;
}

/// An upload's If-Match and query (`id`: PUT's asset, the prefix), or the problem with them.
struct UploadRequest {
    IfMatch condition;
    AssetQuery query;
};
Parsed<UploadRequest> parse_upload_request(const Query& query,
                                           std::optional<std::string_view> content_type,
                                           std::optional<std::string_view> if_match,
                                           std::optional<std::string_view> id) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return Unexpected(problem);
    auto q = parse_query(query, content_type, id, problem);
    if (!q) return Unexpected(problem);
    return UploadRequest{*condition, std::move(*q)};
}

Json id_list(const std::set<std::string>& ids) {
    return Json(std::vector<std::string>(ids.begin(), ids.end()));
}

}  // namespace

ApiResponse post_assets(Engine& engine, std::string body,
                        const std::multimap<std::string, std::string>& query,
                        std::optional<std::string_view> content_type,
                        std::optional<std::string_view> if_match, const ApiLimits& api_limits,
                        const BatchApply* apply) {
    auto request = parse_upload_request(query, content_type, if_match, std::nullopt);
    if (!request) return problem_response(request.error());
    const IfMatch* condition = &request.value().condition;
    const assets::ImportLimits limits = engine.read(
        [&](const Scene& s) { return import_limits(s, api_limits.budget, MeshTotals{}); });
    auto upload =
        read_upload(body, std::move(request.value().query), limits, api_limits.import_sandbox);
    if (!upload) return problem_response(upload.error());
    Upload& u = upload.value();

    // Apply it like any batch; an engine refusal names the id it was creating.
    EditBatch batch = std::move(u.out.batch);  // the answer needs only the lists of ids
    batch.info.message = batch_message("import asset '" + u.q.prefix + "' from " + u.q.name,
                                       "import asset");
    const std::size_t edits = batch.edits.size();
    auto applied = apply ? (*apply)(std::move(batch), condition->version)
                         : engine.apply(std::move(batch), condition->version);
    if (!applied)
        return refused(engine, applied.error(), u.out.edit_ids, u.q.name, u.q.name, "creating",
                       applied.error().code == ErrorCode::DuplicateId
                           ? " (choose another ?prefix=, or PUT /v1/assets/" + u.q.prefix +
                                 " to replace that asset)"
                           : "");
    const ApplyResult& done = applied.value();
    // Where the model landed: the world bounds of the instances it created, to aim at.
    const Json answer = import_answer(u, done, edits, instances_bounds(engine, u.out.instances));
    return with_etag(json_response(200, answer), done.version);
}

ApiResponse get_assets(const Engine& engine) {
    return engine.read([](const Scene& s) {
        Json items = Json::array();
        for (const auto& [id, contents] : scene_assets(s))
            items.push_back(asset_to_json(s, contents, false));
        return with_etag(json_response(200, {{"version", s.version()}, {"assets", items}}),
                         s.version());
    });
}

ApiResponse get_asset(const Engine& engine, std::string_view id) {
    return engine.read([&](const Scene& s) {
        const std::optional<AssetContents> a = find_asset(s, id);
        if (!a) return not_an_asset(id, s.version());
        return with_etag(json_response(200, asset_to_json(s, *a, true)), s.version());
    });
}

ApiResponse delete_asset(Engine& engine, std::string_view id,
                         std::optional<std::string_view> if_match, const BatchApply* apply) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return problem_response(problem);
    const std::string what = "deleting asset '" + std::string(id) + "'";
    for (int attempt = 1;; ++attempt) {
        // Read what the asset owns at one version, and remove exactly that at that version.
        struct Removal {
            uint64_t version = 0;
            std::optional<Json> removed;
            EditBatch batch;
            std::vector<std::string> edit_ids;
        };
        Removal r = engine.read([&](const Scene& s) {
            Removal out;
            out.version = s.version();
            const std::optional<AssetContents> a = find_asset(s, id);
            if (!a) return out;
            Json listed = asset_to_json(s, *a, true);
            out.removed = Json::object();
            for (const char* kind : {"textures", "materials", "meshes", "groups", "instances"})
                (*out.removed)[kind] = std::move(listed[kind]);
            out.batch.edits = removal_edits(s, *a, out.edit_ids);
            out.batch.info.message =
                batch_message("delete asset '" + std::string(id) + "'", "delete asset");
            return out;
        });
        if (!r.removed) return not_an_asset(id, r.version);
        const std::optional<uint64_t> at = condition->version ? condition->version : r.version;
        auto applied = apply ? (*apply)(std::move(r.batch), at) : engine.apply(std::move(r.batch), at);
        if (!applied && applied.error().code == ErrorCode::VersionMismatch &&
            !condition->version && attempt < WRITE_ATTEMPTS)
            continue;  // another writer landed in between: read the asset again
        if (!applied)
            return refused(engine, applied.error(), r.edit_ids, "", what, "removing",
                           applied.error().code == ErrorCode::InUse
                               ? " (an object outside the asset uses it)"
                               : "");
        Json answer = {{"version", applied.value().version},
                       {"applied", applied.value().applied},
                       {"removed", std::move(*r.removed)}};
        return with_etag(json_response(200, answer), applied.value().version);
    }
}

ApiResponse put_asset(Engine& engine, std::string_view id, std::string body,
                      const std::multimap<std::string, std::string>& query,
                      std::optional<std::string_view> content_type,
                      std::optional<std::string_view> if_match, const ApiLimits& api_limits,
                      const BatchApply* apply) {
    auto request = parse_upload_request(query, content_type, if_match, id);
    if (!request) return problem_response(request.error());
    const IfMatch* condition = &request.value().condition;
    // The old asset's meshes leave room for the new ones.
    const assets::ImportLimits limits = engine.read([&](const Scene& s) {
        MeshTotals freed;
        if (const auto old = find_asset(s, id)) {
            for (MeshHandle h : old->meshes) {
                freed.vertices += s.meshes().at(h).positions.size();
                freed.triangles += s.meshes().at(h).triangles.size() + MESH_OVERHEAD_TRIANGLES;
            }
        }
        return import_limits(s, api_limits.budget, freed);
    });
    auto upload = read_upload(body, std::move(request.value().query), limits,
                              api_limits.import_sandbox);
    if (!upload) return problem_response(upload.error());
    const Upload& u = upload.value();
    for (int attempt = 1;; ++attempt) {
        Replacement r = engine.read([&](const Scene& s) { return plan_replacement(s, u); });
        const std::optional<uint64_t> at = condition->version ? condition->version : r.version;
        const std::size_t edits = r.batch.edits.size();
        auto applied = apply ? (*apply)(std::move(r.batch), at) : engine.apply(std::move(r.batch), at);
        if (!applied && applied.error().code == ErrorCode::VersionMismatch &&
            !condition->version && attempt < WRITE_ATTEMPTS)
            continue;
        if (!applied) {
            const Error& e = applied.error();
            return refused(engine, e, r.edit_ids, u.q.name,
                           (r.replaced ? "re-importing asset '" : "importing asset '") +
                               u.q.prefix + "' from " + u.q.name,
                           e.edit_index < r.removals ? "removing" : "creating",
                           e.code == ErrorCode::InUse ? " (an object outside the asset uses it)"
                                                      : "");
        }
        Json answer = import_answer(u, applied.value(), edits,
                                    instances_bounds(engine, u.out.instances));
        answer["replaced"] = r.replaced;
        answer["kept"] = {{"textures", id_list(r.kept.textures)},
                          {"materials", id_list(r.kept.materials)},
                          {"meshes", id_list(r.kept.meshes)}};
        answer["removed"] = r.gone;
        return with_etag(json_response(r.replaced ? 200 : 201, answer), applied.value().version);
    }
}

}  // namespace strata::protocol

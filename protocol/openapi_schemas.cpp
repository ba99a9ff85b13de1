// The components/schemas of the OpenAPI description: what each JSON writer of the protocol
// writes, built from the tables that writer walks wherever there is one (the op table's
// edit-batch schema, the object kinds' field tables, the problem types, ENGINE_COUNTERS and
// DURABLE_COUNTERS, the AOV and format names). The members a writer adds by hand are listed here
// beside the writer's name; the HTTP suites validate every answer against these schemas, so a
// member added to a writer and not here fails them.

#include <algorithm>

#include "engine/accel/report.h"
#include "engine/counters.h"
#include "engine/durable/durable_stats.h"
#include "engine/render/pick.h"
#include "engine/render/render_request.h"
#include "protocol/api.h"
#include "protocol/assets/asset.h"
#include "protocol/field_json.h"
#include "protocol/openapi.h"
#include "protocol/problem.h"
#include "protocol/render_parser.h"

namespace strata::protocol {

namespace {

using J = OrderedJson;

J ref(std::string_view name) {
    return {{"$ref", "#/components/schemas/" + std::string(name)}};
}
J or_null(J schema) {
    return {{"anyOf", J::array({std::move(schema), {{"type", "null"}}})}};
}
J count() {
    return {{"type", "integer"}, {"minimum", 0}};
}
J integer(int64_t lo, int64_t hi) {
    return {{"type", "integer"}, {"minimum", lo}, {"maximum", hi}};
}
J number() {
    return {{"type", "number"}};
}
J boolean() {
    return {{"type", "boolean"}};
}
J string() {
    return {{"type", "string"}};
}
J array_of(J items) {
    return {{"type", "array"}, {"items", std::move(items)}};
}
J described(J schema, std::string_view description) {
    schema["description"] = description;
    return schema;
}
/// The wire names of enum values 0..last, as `name` writes them.
template <class E, class Name>
J names_of(E last, Name&& name) {
    J out = J::array();
    for (int i = 0; i <= int(last); ++i) out.push_back(name(E(i)));
    return {{"enum", std::move(out)}};
}

/// An object with exactly `properties`, each required but those in `optional`.
J object(J properties, std::initializer_list<std::string_view> optional = {}) {
    J required = J::array();
    for (const auto& [key, value] : properties.items()) {
        if (std::find(optional.begin(), optional.end(), key) == optional.end())
            required.push_back(key);
    }
    return {{"type", "object"},
            {"properties", std::move(properties)},
            {"required", std::move(required)},
            {"additionalProperties", false}};
}
/// `a` with the members of `b` after its own.
J merged(J a, const J& b) {
    for (const auto& [key, value] : b.items()) a[key] = value;
    return a;
}
/// Kind `K`'s fields as its documents write them: every one, with its schema and doc.
template <class K>
J fields() {
    return field_properties<K, false>();
}
/// Kind `K`'s label fields (FieldInfo::label: a name, a user id), which picks and tree nodes
/// add to what they say of an object.
template <class K>
J labels() {
    const J all = fields<K>();
    J out = J::object();
    for_each_field<K>([&](const auto& row) {
        const std::string name(row.info.name);
        if (row.info.label) out[name] = all[name];
    });
    return out;
}
J page_of(std::string_view item) {
    return object({{"items", array_of(ref(item))},
                   {"next_cursor",
                    described(or_null(string()), "the cursor of the next page; null on the last")},
                   {"version", count()}});
}

// ---- problems (problem.cpp) ----

/// One member per RFC 9457 field; each type URI with its title and status (the ProblemType
/// table).
J problem_schema() {
    J uris = J::array();
    J cases = J::array();
    for (int i = 0; i <= int(ProblemType::Internal); ++i) {
        const auto t = ProblemType(i);
        uris.push_back(problem_type_uri(t));
        cases.push_back({{"if", {{"properties", {{"type", {{"const", problem_type_uri(t)}}}}}}},
                         {"then",
                          {{"properties",
                            {{"title", {{"const", problem_title(t)}}},
                             {"status", {{"const", problem_status(t)}}}}}}},
                         {"description", problem_when(t)}});
    }
    J s = object({{"type", {{"enum", std::move(uris)}}},
                  {"title", string()},
                  {"status", integer(400, 599)},
                  {"detail", described(string(), "what exactly was wrong")},
                  {"edit_index", described(count(), "the offending edit's position in the batch")},
                  {"pointer", described(string(), "a JSON pointer into the request (RFC 6901)")},
                  {"file", described(string(), "POST /v1/assets: the uploaded file's name")},
                  {"element", described(string(), "POST /v1/assets: the element at fault")}},
                 {"edit_index", "pointer", "file", "element"});
    s["allOf"] = std::move(cases);
    s["description"] = "A problem document (RFC 9457), application/problem+json.";
    return s;
}

// ---- rebuild reports (report_json.cpp) ----

J report_entry_schema() {
    const J reason = names_of(LAST_BUILD_REASON, build_reason_name);
    return object({{"mesh", ref("id")},
                   {"reason", reason},
                   {"primitives", count()},
                   {"clusters", described(count(), "clusters of a clustered BLAS (absent: one "
                                                   "geometry for the whole mesh)")},
                   {"clusters_refit", described(count(), "clusters this commit refit")},
                   {"clusters_rebuilt", described(count(), "clusters this commit built")},
                   {"detail", described(string(), "the refit policy's measured drift")},
                   {"ms", number()},
                   {"bytes", described(count(), "the BLAS's memory after this build")},
                   {"uncompacted_bytes",
                    described(count(), "a compacted mesh's BLAS memory at full size, measured "
                                       "by this build's first pass")}},
                  {"clusters", "clusters_refit", "clusters_rebuilt", "detail", "ms", "bytes",
                   "uncompacted_bytes"});
}

J compaction_schema() {
    return described(object({{"meshes", count()},
                             {"uncompacted_bytes", count()},
                             {"bytes", count()},
                             {"saved_bytes", J{{"type", "integer"}}}}),
                     "the meshes built with build.compact: their BLAS memory at full size "
                     "(measured at their last builds) and compacted");
}

J tlas_report_schema() {
    const J merge = object({{"swapped", boolean()},
                            {"running", boolean()},
                            {"build_ms", number()},
                            {"cancelled", boolean()}},
                           {"build_ms", "cancelled"});
    return object({{"action", names_of(TlasAction::Rebuild, tlas_action_name)},
                   {"instances", count()},
                   {"strategy", {{"enum", {"incremental", "embree"}}}},
                   {"ms", number()},
                   {"static_instances", count()},
                   {"dynamic_instances", count()},
                   {"stale_copies", count()},
                   {"static_array", boolean()},
                   {"dynamic_array", boolean()},
                   {"static_rebuild",
                    {{"enum", {"first_build", "small_scene", "dynamic_tier_full", "requested"}}}},
                   {"merge", merge}},
                  {"ms", "static_instances", "dynamic_instances", "stale_copies", "static_array",
                   "dynamic_array", "static_rebuild", "merge"});
}

J report_schema() {
    const J phases = object({{"plan_ms", number()},
                             {"blas_ms", number()},
                             {"tlas_ms", number()},
                             {"sync_ms", number()}});
    J s = object({{"version", count()},
                  {"planned", boolean()},
                  {"tlas", tlas_report_schema()},
                  {"blas_rebuilds", count()},
                  {"blas_refits", count()},
                  {"rebuilt", array_of(report_entry_schema())},
                  {"refit", array_of(report_entry_schema())},
                  {"released", array_of(ref("id"))},
                  {"primitives_built", count()},
                  {"primitives_refit", count()},
                  {"clusters_rebuilt", count()},
                  {"clusters_refit", count()},
                  {"world_transforms", count()},
                  {"instances_changed", count()},
                  {"memory_bytes", object({{"blas", count()},
                                           {"tlas", count()},
                                           {"compaction", compaction_schema()}})},
                  {"ms", number()},
                  {"phases", phases}},
                 {"ms", "phases"});
    s["description"] =
        "A rebuild report: what a commit did, or (planned) what it would do; a plan has no "
        "time members.";
    return s;
}

// ---- statistics (api.cpp get_stats, durable_json.cpp) ----

template <class Table>
J stat_properties(const Table& table) {
    J properties = J::object();
    for (const auto& spec : table) {
        J s = spec.field.integral() ? count() : number();
        properties[std::string(spec.name)] = described(std::move(s), spec.help);
    }
    return properties;
}

J durability_schema() {
    const J bucket = object(
        {{"le", {{"anyOf", J::array({number(), {{"const", "+Inf"}}})}}}, {"count", count()}});
    J own = {{"directory", string()},
             {"fsync", names_of(durable::FsyncMode::Off, durable::fsync_mode_name)},
             {"failed", boolean()},
             {"failure", string()},
             {"last_snapshot_error", string()},
             {"fsync_latency_seconds", array_of(bucket)}};
    return object(merged(std::move(own), stat_properties(durable::DURABLE_COUNTERS)),
                  {"failure", "last_snapshot_error"});
}

J stats_compaction_schema() {
    J s = compaction_schema();
    s["properties"]["per_mesh"] = array_of(object(
        {{"mesh", ref("id")}, {"uncompacted_bytes", count()}, {"bytes", count()}}));
    s["required"].push_back("per_mesh");
    return s;
}

J stats_schema() {
    return object({{"version", count()},
                   {"counters", object(stat_properties(ENGINE_COUNTERS))},
                   {"last_report", or_null(ref("Report"))},
                   {"memory_bytes",
                    object({{"blas", count()},
                            {"tlas", count()},
                            {"instances", described(count(), "bytes the scene holds for its "
                                                             "instances: records, ids, id map, "
                                                             "lists")},
                            {"per_instance",
                             described(or_null(count()),
                                       "(instances + tlas) / instance count; null without "
                                       "instances")},
                            {"compaction", stats_compaction_schema()}})},
                   {"durability", or_null(ref("Durability"))}});
}

// ---- scene documents (scene_json.cpp) ----

J scene_schema() {
    J counts = J::object();
    for (const char* c : {"meshes", "instances", "materials", "groups", "lights", "textures",
                          "triangles", "instanced_triangles"})
        counts[c] = count();
    return object({{"version", count()},
                   {"counts", object(std::move(counts))},
                   {"bounds", or_null(ref("Bounds"))},
                   {"camera", object(fields<CameraFields>())},
                   {"lighting", object(fields<LightingFields>())},
                   {"timeline", object(fields<TimelineFields>())}});
}

/// The members every object document has before its fields: id and the version it was read at.
J identity(bool indexed) {
    J j = {{"id", ref("id")}};
    if (indexed) j["index"] = described(count(), "its slot: the value the id AOVs hold for it");
    j["version"] = count();
    return j;
}

J material_values() {
    return merged({{"sampler", ref("sampler")}}, fields<MaterialFields>());
}

J mesh_schema() {
    J own = {{"vertices", count()},
             {"triangles", count()},
             {"primitives", described(count(), "triangles, points or curve segments")},
             {"strands", described(count(), "a curve mesh's strands (0 for other kinds)")},
             {"motion_keys",
              described(count(), "its vertex keys over the frame: 1 when still, else 1 + the "
                                 "motion_positions per vertex")},
             {"instances", count()},
             {"material", or_null(ref("id"))},
             {"build", ref("build")}, {"bounds", or_null(ref("Bounds"))}};
    for_each_vertex_attribute([&](auto a) { own[std::string(a.name)] = boolean(); });
    return object(merged(merged(identity(true), own), fields<MeshFields>()));
}

J instance_schema() {
    const J own = {{"mesh", ref("id")},
                   {"material", or_null(ref("id"))},
                   {"resolved_material", object(material_values())},
                   {"parent", or_null(ref("id"))},
                   {"world_transform", ref("transform")},
                   {"world_visible", boolean()},
                   {"bounds", or_null(ref("Bounds"))}};
    return object(merged(merged(identity(true), own), fields<InstanceFields>()));
}

J group_schema() {
    const J own = {{"parent", or_null(ref("id"))},
                   {"world_transform", ref("transform")},
                   {"world_visible", boolean()},
                   {"children", object({{"groups", count()}, {"instances", count()}})},
                   {"bounds", described(or_null(ref("Bounds")),
                                        "world bounds of every instance below it, hidden ones "
                                        "too (null: none); in GET /v1/scene/groups/{id} only")}};
    J s = object(merged(merged(identity(true), own), fields<GroupFields>()));
    J& required = s["required"];
    required.erase(std::find(required.begin(), required.end(), "bounds"));
    return s;
}

J texture_schema() {
    const J own = {{"width", count()},
                   {"height", count()},
                   {"format", {{"enum", {"png", "jpeg", "unknown"}}}},
                   {"encoded_bytes", count()},
                   {"decoded_bytes", count()}};
    return object(merged(merged(identity(false), own), fields<TextureFields>()));
}

J material_schema() {
    J textures = J::object();
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS)
        textures[std::string(slot.field)] = described(or_null(ref("id")), std::string(slot.doc));
    return object(merged(merged(identity(false), textures), material_values()));
}

/// A listing's item with `"kind"` first: a group's children (scene_tree.cpp).
J kind_tagged(std::string_view kind, const J& document) {
    J s = document;
    s["properties"] = merged({{"kind", {{"const", kind}}}}, document["properties"]);
    s["required"].push_back("kind");
    return s;
}

J children_page_schema(const J& group, const J& instance) {
    return object({{"items", array_of({{"anyOf", J::array({kind_tagged("group", group),
                                                           kind_tagged("instance", instance)})}})},
                   {"next_cursor", or_null(string())},
                   {"version", count()}});
}

J tree_schemas(J& out) {
    const J instance = {{"id", ref("id")},
                        {"mesh", ref("id")},
                        {"visible", boolean()},
                        {"world_visible", boolean()}};
    out["TreeInstance"] = object(merged(instance, labels<InstanceFields>()));
    const J group = {{"id", ref("id")},
                     {"visible", boolean()},
                     {"world_visible", boolean()},
                     {"group_count", count()},
                     {"instance_count", count()},
                     {"groups", array_of(ref("TreeGroup"))},
                     {"instances", array_of(ref("TreeInstance"))}};
    out["TreeGroup"] = object(merged(group, labels<GroupFields>()), {"groups", "instances"});
    return object({{"version", count()},
                   {"group", or_null(ref("id"))},
                   {"depth", count()},
                   {"truncated", boolean()},
                   {"groups", array_of(ref("TreeGroup"))},
                   {"instances", array_of(ref("TreeInstance"))}});
}

// ---- renders and picks (render_parser.cpp, pick_parser.cpp, pick_api.cpp) ----

/// A launch's own scene time (a render's or a pick's `time`).
J launch_time() {
    return described(
        {{"type", "number"},
         {"minimum", -int64_t(MAX_SCENE_TIME)},
         {"maximum", int64_t(MAX_SCENE_TIME)}},
        "show the animated instances at this scene time (seconds) instead of the scene's "
        "(set_time), for this launch only: the scene is not changed");
}

J render_request_schema() {
    const RenderRequest d;
    const J side = integer(1, MAX_RENDER_SIDE);
    const J aov = names_of(Aov::UserId, aov_name);
    const J band = {{"type", "array"},
                    {"prefixItems", J::array({integer(0, MAX_RENDER_SIDE - 1), side})},
                    {"minItems", 2},
                    {"maxItems", 2},
                    {"description",
                     "`[y0, rows]`: render only these rows of the frame (internal: what a "
                     "splitting server asks its peers for)"}};
    J props = {
        {"width", described(merged(side, {{"default", d.width}}),
                            "pixels; `width * height` at most `--max-pixels` (413)")},
        {"height", described(merged(side, {{"default", d.height}}), "pixels")},
        {"format",
         described(merged(names_of(ImageFormat::Npz, image_format_name), {{"default", "png"}}),
                   "`npz`: NumPy arrays, one per AOV")},
        {"spp",
         described(merged(integer(1, MAX_RENDER_SPP), {{"default", d.spp}}), "samples per pixel")},
        {"aovs", described(merged(array_of(aov), {{"default", J::array()}}),
                           "extra EXR layers or NPZ arrays")},
        {"compression", described(merged(names_of(ExrCompression::Piz, exr_compression_name),
                                         {{"default", "zip"}}),
                                  "EXR compression")},
        {"accumulate", described(merged(boolean(), {{"default", false}}),
                                 "keep accumulating samples while the scene and camera do not "
                                 "change")},
        {"exposure",
         described({{"type", "number"}, {"minimum", -64}, {"maximum", 64}, {"default", 0}},
                   "EV stops applied before tone mapping")},
        {"time", launch_time()},
        {"filter", described({{"enum", {"none", "atrous"}}, {"default", "none"}},
                             "`atrous`: smooth the colour with an edge-aware à-trous filter "
                             "guided by albedo, normal and depth")},
        {"camera", described(ref("CameraOverride"),
                             "override for this frame only: any of the camera's fields (as "
                             "set_camera takes them); members left out come from the scene "
                             "camera")},
        {"frame",
         merged(described(object({{"group", ref("id")}, {"instance", ref("id")}},
                                 {"group", "instance"}),
                          "aim the camera at a group (its whole subtree) or an instance: the "
                          "scene camera's viewing direction, `up` and `fov_y_deg` (the "
                          "override's when given), the eye moved back until the target's "
                          "bounding sphere fits the frame; exactly one member; not with the "
                          "override's `eye` or `target`"),
                {{"minProperties", 1}, {"maxProperties", 1}, {"x-query-prefix", "frame_"}})},
        {"band", band},
        {"split", described(merged(integer(1, MAX_RENDER_SPLIT), {{"default", 1}}),
                            "render the frame in this many horizontal bands on this server "
                            "and its `--peers`")}};
    J s = object(std::move(props));
    s.erase("required");
    return s;
}

J pixel() {
    return {{"type", "array"},
            {"prefixItems",
             J::array({integer(0, MAX_RENDER_SIDE - 1), integer(0, MAX_RENDER_SIDE - 1)})},
            {"minItems", 2},
            {"maxItems", 2}};
}

void pick_schemas(J& out) {
    const J side = integer(1, MAX_RENDER_SIDE);
    J pixels = array_of(pixel());
    pixels["minItems"] = 1;
    pixels["maxItems"] = MAX_PICK_PIXELS;
    out["PickRequest"] = object({{"width", side},
                                 {"height", side},
                                 {"pixels", std::move(pixels)},
                                 {"camera", ref("CameraOverride")},
                                 {"time", launch_time()}},
                                {"camera", "time"});
    out["PickQuery"] = object({{"x", integer(0, MAX_RENDER_SIDE - 1)},
                               {"y", integer(0, MAX_RENDER_SIDE - 1)},
                               {"width", side},
                               {"height", side},
                               {"camera", ref("CameraOverride")},
                               {"time", launch_time()}},
                              {"camera", "time"});
    const J hit = {{"instance", ref("id")},
                   {"mesh", ref("id")},
                   {"group_path", described(array_of(ref("id")), "the groups from the root down")},
                   {"primitive", count()},
                   {"distance", number()},
                   {"position", ref("vec3")},
                   {"normal", ref("vec3")}};
    out["PickHit"] = object(merged(hit, labels<InstanceFields>()));
    out["PickResult"] = object({{"version", count()}, {"hit", or_null(ref("PickHit"))}});
    out["PickResults"] =
        object({{"version", count()}, {"hits", array_of(or_null(ref("PickHit")))}});
}

// ---- what writes answer (api.cpp, snapshot_api.cpp, assets_api.cpp) and the rest ----

void write_result_schemas(J& out) {
    out["EditResult"] = object({{"version", count()}, {"applied", count()}});
    out["UndoResult"] =
        object({{"version", count()}, {"undone", count()}, {"applied", count()}});
    out["RedoResult"] =
        object({{"version", count()}, {"redone", count()}, {"applied", count()}});
    const J stack = object({{"depth", count()}, {"next", or_null(count())}});
    const J entry = object({{"version", count()},
                            {"time", described(string(), "RFC 3339, UTC, milliseconds")},
                            {"kind", names_of(BatchKind::Redo, batch_kind_name)},
                            {"target", described(count(), "undo, redo: the version taken back or redone")},
                            {"message", described(string(), "the batch's message, when it had one")},
                            {"edits", count()},
                            {"ops", {{"type", "object"}, {"additionalProperties", count()}}},
                            {"undoable", described(boolean(), "on the undo stack now")}},
                           {"target", "message"});
    out["History"] = object({{"version", count()},
                             {"oldest", or_null(count())},
                             {"undo", stack},
                             {"redo", stack},
                             {"held_bytes", count()},
                             {"entries", array_of(entry)},
                             {"next_cursor", or_null(string())}});
    out["SnapshotResult"] =
        object({{"version", count()}, {"applied", count()}, {"snapshot_version", count()}});
    const J ids = array_of(ref("id"));
    out["AssetResult"] =
        object({{"version", count()},
                {"applied", count()},
                {"format", names_of(assets::LAST_ASSET_FORMAT, assets::format_name)},
                {"textures", ids},
                {"meshes", ids},
                {"materials", ids},
                {"groups", ids},
                {"instances", ids},
                {"bounds", described(or_null(ref("Bounds")),
                                     "world bounds of the instances it created (null: none)")},
                {"warnings", array_of(string())},
                {"model", described(string(), "an archive's model: its path inside")}},
               {"model"});
}

/// GET, DELETE and PUT /v1/assets (assets_api.cpp), after AssetResult.
void asset_unit_schemas(J& out) {
    const J ids = array_of(ref("id"));
    J replace = out["AssetResult"];
    replace["properties"]["replaced"] =
        described(boolean(), "true: an asset had the id (200); false: a first import (201)");
    replace["properties"]["kept"] = described(
        object({{"textures", ids}, {"materials", ids}, {"meshes", ids}}),
        "what the new file makes exactly as the scene held it: neither removed nor added, so "
        "no BLAS work");
    replace["properties"]["removed"] =
        described(ids, "what the old asset owned that the new file does not make again");
    for (const char* m : {"replaced", "kept", "removed"}) replace["required"].push_back(m);
    out["AssetReplaceResult"] = std::move(replace);

    // GET /v1/assets (protocol/asset_index.h).
    const J counts = object({{"textures", count()},
                             {"materials", count()},
                             {"meshes", count()},
                             {"groups", count()},
                             {"instances", count()}});
    const J summary = {{"id", ref("id")},
                       {"file", described(string(), "the file it was imported from")},
                       {"name", described(string(), "its group's display name, when it has one")},
                       {"counts", counts},
                       {"bounds", described(or_null(ref("Bounds")),
                                            "world bounds of its instances (null: none)")}};
    out["AssetSummary"] = object(summary, {"name"});
    J one = summary;
    for (const char* kind : {"textures", "materials", "meshes", "groups", "instances"})
        one[kind] = ids;
    out["Asset"] = described(object(one, {"name"}),
                             "An asset: its group (listed first among groups) and every object "
                             "whose id begins with its id and a '.'.");
    out["AssetList"] =
        object({{"version", count()}, {"assets", array_of(ref("AssetSummary"))}});
    out["AssetDeleteResult"] =
        object({{"version", count()},
                {"applied", count()},
                {"removed", object({{"textures", ids},
                                    {"materials", ids},
                                    {"meshes", ids},
                                    {"groups", ids},
                                    {"instances", ids}})}});
}

void misc_schemas(J& out) {
    // /livez and /readyz (server/request_reader.cpp): a section of numbers with --log.
    J health = object({{"status", {{"enum", {"ok", "ready"}}}}});
    health["additionalProperties"] = {{"type", "object"},
                                      {"additionalProperties", number()},
                                      {"description", "with --log: \"replica\", its numbers"}};
    out["Health"] = std::move(health);
    out["CommitEvent"] =
        described(object({{"version", count()}, {"report", or_null(ref("Report"))}}),
                  "The data of a GET /v1/events event (hello and commit).");
}

// ---- named scenes (scenes_api.cpp) ----

void scene_directory_schemas(J& out) {
    J limits = J::object();
    for (const std::string& name : scene_budget_members()) limits[name] = count();
    J some_limits = object(limits);
    some_limits.erase("required");
    out["SceneSettings"] = described(
        object({{"budget", std::move(some_limits)}}, {"budget"}),
        "PUT /v1/scenes/{scene}'s body (optional): budget limits at most the server's flags; "
        "those left out are the flags'");
    out["SceneSummary"] =
        object({{"name", string()},
                {"version", count()},
                {"meshes", count()},
                {"instances", count()},
                {"triangles", count()},
                {"vertices", count()},
                {"memory_bytes", object({{"blas", count()}, {"tlas", count()}})},
                {"durable", described(boolean(), "kept in the data directory")},
                {"budget", object(limits)}});
    out["SceneList"] = object({{"scenes", array_of(ref("SceneSummary"))}});
}

/// Every "$ref": "#/$defs/x" of the edit-batch schema's fragments as "#/components/schemas/x".
void rewrite_refs(J& j) {
    if (j.is_object()) {
        for (auto& [key, value] : j.items()) {
            if (key == "$ref" && value.is_string()) {
                std::string target = value.get<std::string>();
                if (target.starts_with("#/$defs/"))
                    value = "#/components/schemas/" + target.substr(8);
            } else {
                rewrite_refs(value);
            }
        }
    } else if (j.is_array()) {
        for (J& e : j) rewrite_refs(e);
    }
}

/// The edit batch (components EditBatch) and every definition it shares, under their $defs names.
void edit_batch_schemas(J& out) {
    J batch = edit_batch_schema();
    J defs = std::move(batch["$defs"]);
    for (const char* key : {"$defs", "$schema", "$id"}) batch.erase(key);
    out["EditBatch"] = std::move(batch);
    for (auto& [key, value] : defs.items()) out[key] = std::move(value);
}

void scene_schemas(J& out) {
    out["Scene"] = scene_schema();
    out["Bounds"] = object({{"min", ref("vec3")}, {"max", ref("vec3")}});
    J camera = object(fields<CameraFields>());
    camera.erase("required");
    out["CameraOverride"] =
        described(std::move(camera), "members left out come from the scene camera");
    const std::pair<const char*, J> documents[] = {
        {"Mesh", mesh_schema()},
        {"Instance", instance_schema()},
        {"Material", material_schema()},
        {"Group", group_schema()},
        {"Light", object(merged(identity(false), fields<LightFields>()))},
        {"Texture", texture_schema()}};
    for (const auto& [name, schema] : documents) {
        out[name] = schema;
        out[std::string(name) + "Page"] = page_of(name);
    }
    out["ChildrenPage"] = children_page_schema(out["Group"], out["Instance"]);
    out["SceneTree"] = tree_schemas(out);
}

J build_components() {
    J out = J::object();
    edit_batch_schemas(out);
    out["Problem"] = problem_schema();
    out["Report"] = report_schema();
    out["Durability"] = durability_schema();
    out["Stats"] = stats_schema();
    scene_schemas(out);
    out["RenderRequest"] = render_request_schema();
    pick_schemas(out);
    write_result_schemas(out);
    asset_unit_schemas(out);
    misc_schemas(out);
    scene_directory_schemas(out);
    rewrite_refs(out);
    return out;
}

}  // namespace

const OrderedJson& component_schemas() {
    static const OrderedJson schemas = build_components();
    return schemas;
}

}  // namespace strata::protocol

// Named scenes' settings and summaries (/v1/scenes): the JSON half, without the server's
// directory of scenes (server/named_scenes.h).

#include <algorithm>

#include "protocol/api.h"
#include "protocol/json_fields.h"

namespace strata::protocol {

namespace {

/// The settings' members: each a budget field, its wire name, and the server flag it may not
/// exceed.
struct BudgetMember {
    const char* name;
    uint64_t SceneBudget::*field;
    uint64_t unit;  ///< bytes per wire unit (MiB for textures)
    const char* flag;
};

constexpr BudgetMember BUDGET_MEMBERS[] = {
    {"max_triangles", &SceneBudget::max_triangles, 1, "--max-scene-triangles"},
    {"max_vertices", &SceneBudget::max_vertices, 1, "--max-scene-vertices"},
    {"max_instances", &SceneBudget::max_instances, 1, "--max-scene-instances"},
    {"max_texture_mb", &SceneBudget::max_texture_bytes, uint64_t(1) << 20, "--max-texture-mb"},
};

SceneBudget read_settings(FieldReader& r, const Json& v, const SceneBudget& ceiling) {
    r.expect_object(v, "", {"budget"});
    SceneBudget budget = ceiling;
    const Json* b = FieldReader::member(v, "budget");
    if (!b) return budget;
    static const MemberRule MEMBERS{scene_budget_members(), {}};
    r.expect_object(*b, "/budget", MEMBERS);
    for (const BudgetMember& m : BUDGET_MEMBERS) {
        const Json* f = FieldReader::member(*b, m.name);
        if (!f) continue;
        const uint64_t most = ceiling.*m.field / m.unit;
        const std::string ptr = std::string("/budget/") + m.name;
        const uint64_t value = r.integer(*f, ptr, 0, UINT64_MAX / m.unit);
        if (value > most) {
            r.record_value_error(ptr, std::string(m.name) + " " + std::to_string(value) +
                                          " is over this server's limit of " +
                                          std::to_string(most) + " (" + m.flag + ")");
        }
        budget.*m.field = value * m.unit;
    }
    return budget;
}

}  // namespace

bool valid_scene_name(std::string_view name) {
    if (name.empty() || name.size() > MAX_SCENE_NAME_BYTES) return false;
    const auto allowed = [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    };
    const char first = name.front();
    return std::all_of(name.begin(), name.end(), allowed) && first != '-' && first != '_';
}

Parsed<SceneBudget> parse_scene_settings(std::string_view body, const SceneBudget& ceiling,
                                         const JsonLimits& limits) {
    if (body.find_first_not_of(" \t\r\n") == std::string_view::npos) return ceiling;
    auto json = parse_json(body, limits);
    if (!json) return Unexpected(std::move(json).error());
    FieldReader r;
    try {
        SceneBudget budget = read_settings(r, json.value(), ceiling);
        if (r.value_error()) return Unexpected(*r.value_error());
        return budget;
    } catch (const RequestFailure& f) {
        return Unexpected(f.problem());
    }
}

std::vector<std::string> scene_budget_members() {
    std::vector<std::string> out;
    for (const BudgetMember& m : BUDGET_MEMBERS) out.emplace_back(m.name);
    return out;
}

Json scene_settings_json(const SceneBudget& budget) {
    Json b = Json::object();
    for (const BudgetMember& m : BUDGET_MEMBERS) b[m.name] = budget.*m.field / m.unit;
    return {{"budget", std::move(b)}};
}

Json scene_summary_json(std::string_view name, const Engine& engine, const SceneBudget& budget,
                        bool durable) {
    const auto [version, totals] = engine.read(
        [](const Scene& s) { return std::pair(s.version(), s.mesh_totals()); });
    Json out = {{"name", name},
                {"version", version},
                {"meshes", totals.meshes},
                {"instances", totals.instances},
                {"triangles", totals.triangles},
                {"vertices", totals.vertices},
                {"memory_bytes",
                 {{"blas", engine.memory_bytes(MemoryCategory::Blas)},
                  {"tlas", engine.memory_bytes(MemoryCategory::Tlas)}}},
                {"durable", durable}};
    out.update(scene_settings_json(budget));
    return out;
}

}  // namespace strata::protocol

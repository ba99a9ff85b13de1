// GET and POST /v1/pick: one ray per asked pixel of the committed scene, no frame.

#include "protocol/api.h"
#include "protocol/field_json.h"
#include "protocol/pick_parser.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

namespace {

Json hit_to_json(const std::optional<PickHit>& hit) {
    if (!hit) return nullptr;
    Json j = {{"instance", hit->instance},
              {"mesh", hit->mesh},
              {"group_path", hit->group_path},
              {"primitive", hit->primitive},
              {"distance", float_to_json(hit->distance)},
              {"position", vec3_to_json(hit->position)},
              {"normal", vec3_to_json(hit->normal)}};
    write_labels<InstanceFields>(j, hit->fields);
    return j;
}

/// Picks; `answer` turns the result into the body.
template <class Answer>
ApiResponse pick(Engine& engine, const Parsed<PickRequest>& request, Answer&& answer) {
    if (!request) return problem_response(request.error());
    auto picked = engine.pick(request.value());
    if (!picked) return problem_response(problem_from(picked.error()));
    return with_etag(json_response(200, answer(picked.value())), picked.value().version);
}

}  // namespace

ApiResponse get_pick(Engine& engine, const std::multimap<std::string, std::string>& query) {
    return pick(engine, parse_pick_query(query), [](const PickResult& r) {
        return Json{{"version", r.version}, {"hit", hit_to_json(r.hits.at(0))}};
    });
}

ApiResponse post_pick(Engine& engine, std::string_view body, const ApiLimits& limits) {
    auto doc = parse_json(body, limits.json);
    if (!doc) return problem_response(doc.error());
    return pick(engine, parse_pick_body(doc.value()), [](const PickResult& r) {
        Json hits = Json::array();
        for (const auto& h : r.hits) hits.push_back(hit_to_json(h));
        return Json{{"version", r.version}, {"hits", std::move(hits)}};
    });
}

}  // namespace strata::protocol

#include "protocol/api.h"

#include <cctype>
#include <charconv>
#include <chrono>

#include "protocol/durable_json.h"
#include "protocol/edit_parser.h"
#include "protocol/render_parser.h"
#include "protocol/report_json.h"
#include "protocol/safe_text.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

namespace {

uint64_t scene_version(const Engine& engine) {
    return engine.read([](const Scene& s) { return s.version(); });
}

/// The body of every JSON answer, problems included: one line of JSON and a newline, so that a
/// shell prompt after `curl` starts on a line of its own and JSON Lines tools read it as is.
std::string json_body(const Json& j) {
    std::string text = dump_json(j);
    text += '\n';
    return text;
}

std::string_view trim(std::string_view v) {
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.remove_suffix(1);
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    return v;
}

/// Largest X-Strata-Report value. Clients and proxies bound response headers tightly:
/// cpp-httplib (our CLI's client) refuses a header line over 8 KiB, nginx a header block over
/// its 4 KiB proxy_buffer_size by default. 3 KiB leaves the rest of the answer's header room.
constexpr std::size_t MAX_REPORT_HEADER = 3 * 1024;

/// The report of a render's commit as one header value (compact JSON). A report too long for a
/// header keeps its counts but lists only the first entries of `rebuilt`, `refit` and
/// `released`, and says so with `"entries_truncated": true`.
std::string report_header(const RebuildReport& report) {
    std::string text = dump_json(report_to_json(report));
    std::size_t keep =
        std::max({report.rebuilt.size(), report.refit.size(), report.released.size()});
    while (text.size() > MAX_REPORT_HEADER && keep > 0) {
        keep /= 2;
        RebuildReport shorter = report;
        shorter.rebuilt.resize(std::min(keep, shorter.rebuilt.size()));
        shorter.refit.resize(std::min(keep, shorter.refit.size()));
        shorter.released.resize(std::min(keep, shorter.released.size()));
        Json j = report_to_json(shorter);
        j["entries_truncated"] = true;
        text = dump_json(j);
    }
    return text;
}

/// A render's `frame` (when `target` holds an id) as its camera override, from the scene as it
/// is now: the launch may render a newer version, with the eye and target this one framed.
Parsed<void> aim(const Engine& engine, RenderRequest& request,
                 const std::optional<FrameTarget>& target) {
    if (!target) return {};
    const float aspect = float(request.width) / float(request.height);
    auto camera = engine.read(
        [&](const Scene& s) { return framed_override(s, *target, request.camera, aspect); });
    if (!camera) return Unexpected(std::move(camera).error());
    request.camera = std::move(camera).value();
    return {};
}

ApiResponse render(Engine& engine, RenderRequest request, const ApiLimits& limits,
                   CancelToken* cancel, uint32_t split = 1,
                   const SplitRender* split_render = nullptr) {
    const RenderRequest& q0 = request;
    const uint64_t pixels = uint64_t(q0.width) * q0.height;
    if (pixels > limits.max_pixels) {
        Problem p =
            make_problem(ProblemType::TooLarge,
                         std::to_string(q0.width) + "x" + std::to_string(q0.height) + " is " +
                             std::to_string(pixels) + " pixels; this server renders at most " +
                             std::to_string(limits.max_pixels) + " (--max-pixels)");
        p.pointer = "/width";
        return problem_response(p);
    }
    CancelToken own;
    CancelToken& token = cancel ? *cancel : own;
    if (limits.render_timeout_s > 0)
        token.set_deadline(CancelToken::Clock::now() +
                           std::chrono::seconds(limits.render_timeout_s));
    request.cancel = &token;
    std::string bands;
    // The filter reads each pixel's measured noise from 2 samples on, which bands do not carry:
    // such a frame is rendered here whole, so that it stays the bytes of an unsplit render.
    const bool whole = split > 1 && request.filter && request.spp > 1;
    Result<EncodedFrame> image = [&]() -> Result<EncodedFrame> {
        if (split <= 1 || whole) {
            // A camera override's missing fields come from the camera of the version the
            // launch renders.
            return engine.render(request);
        }
        if (!split_render)
            return failure(ErrorCode::InvalidArgument,
                           "this server has no peers to split a frame across (--peers)", "split");
        if (Status s = check_render_request(request); !s) return Unexpected(s.error());
        auto frame = (*split_render)(request, split);
        if (!frame) return Unexpected(frame.error());
        bands = std::move(frame->bands);
        return std::move(frame->frame);
    }();
    if (!image && image.error().code == ErrorCode::Cancelled &&
        token.reason() == CancelReason::Deadline)
        return problem_response(make_problem(
            ProblemType::DeadlineExceeded,
            "the render did not finish within " + std::to_string(limits.render_timeout_s) +
                " s (--render-timeout) and was stopped; ask for fewer pixels or samples, or "
                "accumulate several shorter renders"));
    if (!image) return problem_response(problem_from(image.error()));
    EncodedFrame& frame = image.value();
    if (whole)
        bands = "1 band at version " + std::to_string(frame.info.version) +
                ": local (not split: a filtered frame of more than 1 sample needs each pixel's "
                "noise, which bands do not carry)";
    ApiResponse r;
    r.status = 200;
    r.content_type = std::move(frame.content_type);
    r.body = std::move(frame.bytes);
    r.headers = {{"ETag", etag(frame.info.version)},
                 {"X-Strata-Rebuild", frame.info.report.summary()},
                 {"X-Strata-Report", report_header(frame.info.report)},
                 {"X-Strata-Samples", std::to_string(frame.info.samples)},
                 {"Cache-Control", "no-store"}};
    if (!bands.empty()) r.headers.emplace_back("X-Strata-Split", std::move(bands));
    r.commit = std::move(frame.info.report);
    return r;
}

}  // namespace

std::string_view ApiResponse::header(std::string_view name) const {
    for (const auto& [key, value] : headers)
        if (key == name) return value;
    return {};
}

ApiResponse with_etag(ApiResponse r, uint64_t version) {
    r.headers.emplace_back("ETag", etag(version));
    return r;
}

std::optional<Problem> json_body_type_problem(std::optional<std::string_view> content_type) {
    if (!content_type) return std::nullopt;
    std::string type(content_type->substr(0, content_type->find(';')));
    while (!type.empty() && (type.back() == ' ' || type.back() == '\t')) type.pop_back();
    while (!type.empty() && (type.front() == ' ' || type.front() == '\t')) type.erase(0, 1);
    for (char& c : type) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (type.empty() || type == "application/json" || type.ends_with("+json") ||
        type == "text/plain" || type == "application/x-www-form-urlencoded")
        return std::nullopt;
    return make_problem(ProblemType::UnsupportedMedia,
                        "this endpoint reads a JSON body; Content-Type '" + escape_for_log(type) +
                            "' is not one it reads (send application/json)");
}

ApiResponse json_response(int status, const Json& body) {
    ApiResponse r;
    r.status = status;
    r.content_type = "application/json";
    r.body = json_body(body);
    return r;
}

ApiResponse problem_response(const Problem& problem) {
    ApiResponse r;
    r.status = problem.status;
    r.content_type = "application/problem+json";
    r.body = json_body(problem_to_json(problem));
    return r;
}

std::string etag(uint64_t version) {
    return "\"" + std::to_string(version) + "\"";
}

std::optional<IfMatch> parse_if_match(std::string_view value, Problem& problem) {
    std::string_view v = trim(value);
    if (v == "*") return IfMatch{};
    auto bad = [&](const std::string& why) -> std::optional<IfMatch> {
        problem = make_problem(ProblemType::InvalidRequest,
                               "If-Match: " + why + " (expected an entity tag such as \"12\")");
        return std::nullopt;
    };
    if (v.find(',') != std::string_view::npos)
        return bad("lists of several entity tags are not supported");
    if (v.substr(0, 2) == "W/") {
        // A weak tag never matches under the strong comparison If-Match requires.
        return IfMatch{UINT64_MAX};
    }
    if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
    uint64_t n = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size())
        return bad("'" + std::string(value) + "' is not a Strata entity tag");
    return IfMatch{n};
}

ApiResponse post_edits(Engine& engine, std::string body, std::optional<std::string_view> if_match,
                       const ApiLimits& limits, const BatchApply* apply) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return problem_response(problem);

    auto parsed = parse_edit_batch(body, limits.json, limits.max_batch_edits);
    body = {};  // the DOM and the batch hold what is needed; free the text early
    if (!parsed) return problem_response(parsed.error());
    ParsedBatch& batch = parsed.value();

    auto applied = apply ? (*apply)(std::move(batch.batch), condition->version)
                         : engine.apply(std::move(batch.batch), condition->version);
    if (!applied) {
        const Error& e = applied.error();
        if (e.code == ErrorCode::VersionMismatch) {
            // The current version, ready for a read-modify-write retry.
            return with_etag(problem_response(make_problem(ProblemType::VersionMismatch,
                                                           "If-Match: " + e.message)),
                             scene_version(engine));
        }
        return problem_response(problem_from_batch_error(e, batch.sources));
    }
    const ApplyResult& done = applied.value();
    return with_etag(json_response(200, {{"version", done.version}, {"applied", done.applied}}),
                     done.version);
}

ApiResponse post_commit(Engine& engine) {
    auto report = engine.commit();
    if (!report) return problem_response(problem_from(report.error()));
    ApiResponse r =
        with_etag(json_response(200, report_to_json(report.value())), report.value().version);
    r.commit = std::move(report.value());
    return r;
}

ApiResponse get_plan(const Engine& engine) {
    RebuildReport plan = engine.plan();
    // A plan's memory is what the acceleration structures hold now, before the commit.
    plan.memory_blas_bytes = engine.memory_bytes(MemoryCategory::Blas);
    plan.memory_tlas_bytes = engine.memory_bytes(MemoryCategory::Tlas);
    plan.compaction = engine.compaction().totals;
    return with_etag(json_response(200, report_to_json(plan)), plan.version);
}

ApiResponse post_render(Engine& engine, std::string_view body, const ApiLimits& limits,
                        CancelToken* cancel, const SplitRender* split_render) {
    // An empty body means every default, like GET without a query.
    auto doc = body.empty() ? Parsed<Json>(Json::object()) : parse_json(body, limits.json);
    if (!doc) return problem_response(doc.error());
    uint32_t split = 1;
    std::optional<FrameTarget> frame;
    auto spec = parse_render_body(doc.value(), &split, &frame);
    if (!spec) return problem_response(spec.error());
    if (auto ok = aim(engine, spec.value(), frame); !ok) return problem_response(ok.error());
    return render(engine, spec.value(), limits, cancel, split, split_render);
}

ApiResponse get_render(Engine& engine, const std::multimap<std::string, std::string>& query,
                       const ApiLimits& limits, CancelToken* cancel,
                       const SplitRender* split_render) {
    uint32_t split = 1;
    std::optional<FrameTarget> frame;
    auto spec = parse_render_query(query, &split, &frame);
    if (!spec) return problem_response(spec.error());
    if (auto ok = aim(engine, spec.value(), frame); !ok) return problem_response(ok.error());
    return render(engine, spec.value(), limits, cancel, split, split_render);
}

ApiResponse get_scene(const Engine& engine) {
    const Json doc = engine.read([](const Scene& s) { return scene_summary_to_json(s); });
    return with_etag(json_response(200, doc), doc["version"].get<uint64_t>());
}

ApiResponse get_scene_object(const Engine& engine, SceneObject kind, std::string_view id) {
    using ToJson = std::optional<Json> (*)(const Scene&, std::string_view);
    static constexpr ToJson TO_JSON[] = {mesh_to_json,  instance_to_json, material_to_json,
                                         group_to_json, light_to_json,    texture_to_json};
    static constexpr const char* NAMES[] = {"mesh",  "instance", "material",
                                            "group", "light",    "texture"};
    // One read lock: the document and its version belong together.
    auto [doc, version] = engine.read(
        [&](const Scene& s) { return std::pair(TO_JSON[int(kind)](s, id), s.version()); });
    if (!doc)
        return with_etag(problem_response(make_problem(ProblemType::NotFound,
                                                       std::string("no ") + NAMES[int(kind)] +
                                                           " with id '" + std::string(id) + "'")),
                         version);
    return with_etag(json_response(200, *doc), version);
}

ApiResponse get_stats(const Engine& engine, const durable::DurableStats* durable) {
    const EngineCounters counters = engine.counters();
    const RebuildReport last = engine.last_report();
    const auto [version, instances, instance_bytes] = engine.read([](const Scene& s) {
        return std::tuple(s.version(), uint64_t(s.instances().size()), s.instance_bytes());
    });
    const int64_t tlas = engine.memory_bytes(MemoryCategory::Tlas);
    const uint64_t per_instance_bytes = instance_bytes + uint64_t(std::max<int64_t>(tlas, 0));
    const CompactionSummary compacted = engine.compaction();
    Json compaction = compaction_to_json(compacted.totals);
    Json& per_mesh = compaction["per_mesh"] = Json::array();
    for (const CompactedBlas& m : compacted.meshes)
        per_mesh.push_back(
            {{"mesh", m.mesh}, {"uncompacted_bytes", m.uncompacted_bytes}, {"bytes", m.bytes}});
    const Json doc = {
        {"version", version},
        {"counters", counters_to_json(counters)},
        {"last_report", counters.commits ? report_to_json(last) : Json(nullptr)},
        {"memory_bytes",
         {{"blas", engine.memory_bytes(MemoryCategory::Blas)},
          {"tlas", tlas},
          {"instances", instance_bytes},
          {"per_instance", instances ? Json(per_instance_bytes / instances) : Json(nullptr)},
          {"compaction", std::move(compaction)}}}};
    Json out = doc;
    out["durability"] = durable ? durable_stats_to_json(*durable) : Json(nullptr);
    return with_etag(json_response(200, out), version);
}

}  // namespace strata::protocol

// GET /v1/stream (the live viewer's JPEG frames) and GET /v1/events (commit events): the
// handlers check the request and open a stream on the hub (stream_hub.h); the front end then
// writes it (reactor.h, Streaming) without holding a worker.

#include <charconv>
#include <cmath>

#include "engine/render/accumulator.h"
#include "protocol/render_parser.h"
#include "protocol/report_json.h"
#include "protocol/safe_text.h"
#include "server/context.h"
#include "server/past_version_query.h"
#include "server/route_table.h"
#include "server/stream_hub.h"

namespace strata::server {

namespace {

using protocol::ProblemType;

/// Bounds of the stream-only parameters.
constexpr double MAX_STREAM_FPS = 60.0;
constexpr uint32_t MAX_STREAM_SAMPLES = 4096;
/// GET /v1/render's parameters a stream refuses: its frames are JPEG, accumulating.
constexpr const char* RENDER_ONLY[] = {"format", "aovs", "compression", "accumulate", "band"};

protocol::Problem bad_parameter(const std::string& name, const std::string& detail) {
    protocol::Problem p = protocol::make_problem(ProblemType::InvalidRequest, detail);
    p.pointer = "/" + name;
    return p;
}

/// Takes `name` out of `params` as a number in [lo, hi]; `out` keeps its default when absent.
template <class T>
std::optional<protocol::Problem> take_number(std::multimap<std::string, std::string>& params,
                                             const std::string& name, T lo, T hi, T& out) {
    auto it = params.find(name);
    if (it == params.end()) return std::nullopt;
    const std::string text = it->second;
    params.erase(it);
    double v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) ||
        v < double(lo) || v > double(hi) || (std::is_integral_v<T> && v != std::floor(v)))
        return bad_parameter(name, "query parameter '" + name + "' must be a" +
                                       (std::is_integral_v<T> ? "n integer" : " number") +
                                       " from " + protocol::Json(lo).dump() + " to " +
                                       protocol::Json(hi).dump() + ", not '" + text + "'");
    out = T(v);
    return std::nullopt;
}

/// The stream's parameters: fps, quality and max_samples of its own, the rest as GET
/// /v1/render reads them (protocol/render_parser.h).
std::variant<ViewerSpec, protocol::Problem> parse_viewer(
    std::multimap<std::string, std::string> params, const protocol::ApiLimits& limits) {
    ViewerSpec spec;
    if (auto p = take_number(params, "fps", 0.1, MAX_STREAM_FPS, spec.fps)) return *p;
    if (auto p = take_number(params, "quality", 1, 100, spec.quality)) return *p;
    if (auto p = take_number(params, "max_samples", 1u, MAX_STREAM_SAMPLES, spec.max_samples))
        return *p;
    // An opaque value that makes a viewer's URL its own: browsers share one in-flight image
    // between equal URLs, so a reloaded page would wait on the stream of the page it replaced.
    if (auto it = params.find("client"); it != params.end()) params.erase(it);
    // The selected instance, tinted per viewer after the shared render: not part of the view.
    if (auto it = params.find("highlight"); it != params.end()) {
        spec.highlight = it->second;
        params.erase(it);
        if (spec.highlight.empty())
            return bad_parameter("highlight",
                                 "query parameter 'highlight' must name an instance, not ''");
    }
    for (const char* fixed : RENDER_ONLY) {
        if (params.count(fixed))
            return bad_parameter(fixed, std::string("query parameter '") + fixed +
                                            "' does not apply to /v1/stream: frames are JPEG, "
                                            "accumulating up to max_samples");
    }
    // The edge-aware filter is on by default here, unlike GET /v1/render: a viewer shows few
    // samples per pixel while it moves, and the filter follows each pixel's noise, so it leaves
    // a converged frame (almost) as it is. `filter=none` turns it off.
    if (!params.count("filter")) params.emplace("filter", "atrous");
    // Equal render parameters share renders; the per-viewer pace does not split a view.
    spec.key = "q=" + std::to_string(spec.quality) + "&s=" + std::to_string(spec.max_samples);
    for (const auto& [name, value] : params) spec.key += "&" + name + "=" + value;
    auto request = protocol::parse_render_query(params);
    if (!request) return request.error();
    spec.request = std::move(request.value());
    const uint64_t pixels = uint64_t(spec.request.width) * spec.request.height;
    if (pixels > std::min<uint64_t>(limits.max_pixels, MAX_ACCUMULATE_PIXELS)) {
        protocol::Problem p = protocol::make_problem(
            ProblemType::TooLarge, std::to_string(spec.request.width) + "x" +
                                       std::to_string(spec.request.height) +
                                       " is more pixels than a stream renders (--max-pixels)");
        p.pointer = "/width";
        return p;
    }
    if (Status s = check_render_request(spec.request); !s) return protocol::problem_from(s.error());
    return spec;
}

/// GET only: the headers of a stream exist only as the stream starts.
std::optional<protocol::ApiResponse> refuse_head(const HttpRequest& req) {
    if (req.method != "HEAD") return std::nullopt;
    protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
        ProblemType::MethodNotAllowed, "HEAD " + req.path + " is not served: use GET"));
    r.headers.emplace_back("Allow", "GET");
    return r;
}

protocol::Problem stream_unavailable() {
    return protocol::make_problem(ProblemType::Unavailable,
                                  "the server is shutting down; streams are closed");
}

/// The head of a stream: 200, `content_type`, never cached, then `preamble`.
protocol::ApiResponse stream_head(const char* content_type, std::string preamble) {
    protocol::ApiResponse head;
    head.content_type = content_type;
    head.headers.emplace_back("Cache-Control", "no-store");
    head.body = std::move(preamble);
    return head;
}

/// The problem of a highlight naming no instance of the scene shown, if it does not.
std::optional<protocol::Problem> unknown_highlight(Engine& shown, const std::string& id) {
    if (id.empty()) return std::nullopt;
    const bool known = shown.read([&](const Scene& s) { return !s.find_instance(id).is_null(); });
    if (known) return std::nullopt;
    protocol::Problem p = protocol::make_problem(ProblemType::NotFound,
                                                 "highlight: no instance with id '" + id + "'");
    p.pointer = "/highlight";
    return p;
}

/// The problem of a camera override the scene's camera cannot be completed into a usable one.
std::optional<protocol::Problem> unusable_camera(Engine& shown, const RenderRequest& r) {
    if (!r.camera) return std::nullopt;
    const Status usable = shown.read([&](const Scene& s) -> Status {
        auto camera = resolve_camera(r.camera, s.camera());
        if (!camera) return Unexpected(camera.error());
        return {};
    });
    if (usable) return std::nullopt;
    return protocol::problem_from(usable.error());
}

/// A stream refused for memory (its view's, or a past version's): 503, try again later.
protocol::ApiResponse streams_full(const Error& e) {
    protocol::ApiResponse r =
        protocol::problem_response(protocol::make_problem(ProblemType::Unavailable, e.message));
    r.headers.emplace_back("Retry-After", "5");
    return r;
}

/// Gives `spec` the scene at the version `asked` names, if any (its view apart from the live
/// one's); a problem when that version cannot be had.
std::optional<Reply> hold_past_version(ServerContext& ctx, std::optional<uint64_t> asked,
                                       ViewerSpec& spec) {
    if (!asked) return std::nullopt;
    auto past = ctx.past->for_stream(ctx.engine, ctx.store, *asked);
    if (!past && past.error().code == ErrorCode::TooLarge) return streams_full(past.error());
    if (!past) return past_version_problem(past.error());
    spec.past = std::move(past.value());
    spec.key += "&at_version=" + std::to_string(*asked);
    return std::nullopt;
}

Reply open_frame_stream(ServerContext& ctx, RouteCall& call) {
    if (auto refusal = refuse_head(call.request)) return std::move(*refusal);
    auto query = call.request.query;
    auto asked = asked_version(ctx.engine, query);
    if (!asked) return std::move(asked.error());
    auto parsed = parse_viewer(std::move(query), ctx.api_limits);
    if (auto* p = std::get_if<protocol::Problem>(&parsed)) return *p;
    ViewerSpec& spec = std::get<ViewerSpec>(parsed);
    if (auto refusal = hold_past_version(ctx, asked.value(), spec)) return std::move(*refusal);
    Engine& shown = spec.past ? *spec.past : ctx.engine;
    // An unknown instance is refused at once (a typo would otherwise tint nothing, silently);
    // one removed later simply stops being tinted.
    if (auto p = unknown_highlight(shown, spec.highlight)) return *p;
    // So is a camera no frame can be rendered with: answered now, not by a stream that starts
    // and then sends nothing.
    if (auto p = unusable_camera(shown, spec.request)) return *p;
    if (!ctx.streams) return stream_unavailable();
    auto watched = ctx.streams->watch(std::move(spec));
    if (!watched) return streams_full(watched.error());
    std::shared_ptr<StreamChannel> channel = std::move(watched.value());
    if (!channel) return stream_unavailable();
    return Reply::streaming(stream_head("multipart/x-mixed-replace; boundary=strata-frame",
                                        "--strata-frame\r\nContent-Type: image/jpeg\r\n\r\n"),
                            std::move(channel));
}

Reply open_event_stream(ServerContext& ctx, RouteCall& call) {
    if (auto refusal = refuse_head(call.request)) return std::move(*refusal);
    const auto& query = call.request.query;
    if (!query.empty())
        return bad_parameter(query.begin()->first, "GET /v1/events takes no query parameter ('" +
                                                       query.begin()->first + "')");
    if (!ctx.streams) return stream_unavailable();
    // The first event says where the scene stands: its version and the last commit's report
    // (null before the first commit).
    const EngineCounters counters = ctx.engine.counters();
    const uint64_t version = ctx.engine.read([](const Scene& s) { return s.version(); });
    const protocol::Json hello = {
        {"version", version},
        {"report", counters.commits ? protocol::report_to_json(ctx.streams->last_commit())
                                    : protocol::Json(nullptr)}};
    auto channel = ctx.streams->subscribe();
    if (!channel) return stream_unavailable();
    return Reply::streaming(stream_head("text/event-stream", "retry: 2000\n\nevent: hello\ndata: " +
                                                                 protocol::dump_json(hello) +
                                                                 "\n\n"),
                            std::move(channel));
}

/// GET /v1/stream's parameters: the render's that apply (filter on by default), then its own.
std::vector<protocol::ParamDoc> frame_stream_parameters() {
    // split and frame are no stream's either (unknown parameters); filter is documented below.
    std::vector<std::string> leave_out(std::begin(RENDER_ONLY), std::end(RENDER_ONLY));
    leave_out.insert(leave_out.end(), {"split", "filter", "frame"});
    std::vector<protocol::ParamDoc> params = protocol::query_parameters("RenderRequest", leave_out);
    using J = protocol::OrderedJson;
    const auto bounded = [](const char* type, J lo, J hi, J fallback) {
        return J{{"type", type}, {"minimum", lo}, {"maximum", hi}, {"default", fallback}}.dump();
    };
    params.push_back({.name = "filter",
                      .description = "the edge-aware filter, on by default here; none shows the "
                                     "raw samples",
                      .schema = R"({"enum": ["none", "atrous"], "default": "atrous"})"});
    params.push_back({.name = "fps",
                      .description = "most frames per second sent to this client",
                      .schema = bounded("number", 0.1, MAX_STREAM_FPS, ViewerSpec{}.fps)});
    params.push_back({.name = "quality",
                      .description = "JPEG quality",
                      .schema = bounded("integer", 1, 100, ViewerSpec{}.quality)});
    params.push_back(
        {.name = "max_samples",
         .description = "accumulation stops improving a frame at this many samples",
         .schema = bounded("integer", 1, MAX_STREAM_SAMPLES, ViewerSpec{}.max_samples)});
    params.push_back({.name = "highlight",
                      .description = "an instance id: its pixels tinted and outlined in every "
                                     "frame of this stream"});
    params.push_back({.name = "client",
                      .description = "ignored: makes a viewer's URL its own (browsers share one "
                                     "in-flight image between equal URLs)"});
    return params;
}

}  // namespace

void add_stream_routes(RouteTable& routes, ServerContext& ctx) {
    using protocol::problem;
    const protocol::ResponseDoc head = problem(405,
                                               "HEAD: a stream's headers exist only as it "
                                               "starts; use GET",
                                               {"Allow"});
    const protocol::ResponseDoc closed = problem(503, "the server is shutting down");
    protocol::RouteDoc frames{
        .summary = "Live JPEG frames of the scene (multipart/x-mixed-replace)",
        .description = "Each part a JPEG whose comment says `strata version=V samples=S`; a new "
                       "frame when the version changes or accumulation improves it. An <img "
                       "src> shows it. With at_version, the frames show that version and stop "
                       "once they reach max_samples.",
        .tag = "stream",
        .parameters = frame_stream_parameters(),
        .responses = {{.status = 200,
                       .description = "the stream, until the client leaves or the server "
                                      "shuts down",
                       .media = {"multipart/x-mixed-replace"},
                       .headers = {"Cache-Control"}},
                      problem(400, "a parameter that does not apply, or a malformed one"),
                      problem(404, "highlight names no instance (pointer /highlight)"),
                      head,
                      problem(413, "more pixels than a stream renders"),
                      problem(422, "a value the renderer cannot use"),
                      problem(503,
                              "the server is shutting down, or open streams hold all the "
                              "memory they may (--max-stream-mb) or all the past versions",
                              {"Retry-After"})},
        .query_token = true};
    describe_past_version(frames,
                          "loaded from the data directory as for GET /v1/render (at the live "
                          "version too, so that the stream stays there as the scene moves on); "
                          "the stream holds it while it is open, streams of one version share "
                          "it, and streams may hold 4 versions at once (then 503)");
    routes.get("/v1/stream", {std::move(frames),
                              [&ctx](RouteCall& call) { return open_frame_stream(ctx, call); }});
    routes.get(
        "/v1/events",
        {{.summary = "Commit events (Server-Sent Events)",
          .description = "A hello event, then one commit event per commit that brought edits "
                         "in; each event's data is a CommitEvent document.",
          .tag = "stream",
          .responses = {{.status = 200,
                         .description = "the event stream",
                         .media = {"text/event-stream"},
                         .headers = {"Cache-Control"}},
                        problem(400, "any query parameter"),
                        head,
                        closed},
          .query_token = true},
         [&ctx](RouteCall& call) { return open_event_stream(ctx, call); }});
}

}  // namespace strata::server

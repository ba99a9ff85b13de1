#include "protocol/openapi.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "engine/core/check.h"
#include "protocol/problem.h"

namespace strata::protocol {

namespace {

using J = OrderedJson;

/// What the front end answers on any route before the route table sees the request
/// (server/request_reader.cpp, reactor.cpp): listed on every operation, as a reference to
/// components/responses where the route says nothing of its own about that status.
struct Refusal {
    ProblemType type;
    const char* when;
    const char* header = nullptr;
};
constexpr Refusal FRONT_END_REFUSALS[] = {
    {ProblemType::Unauthorized, "a token is needed and the request has none, or not this one",
     "WWW-Authenticate"},
    {ProblemType::Forbidden,
     "with --tokens-file: the token's role in this scene does not allow the request"},
    {ProblemType::InvalidRequest,
     "a malformed HTTP request or query (a bad percent-escape, invalid UTF-8, a control "
     "character, a repeated parameter)"},
    {ProblemType::RequestTimeout,
     "the request did not arrive within --header-timeout or --read-timeout"},
    {ProblemType::TooLarge, "a body larger than --max-body-mb"},
    {ProblemType::UriTooLong, "a request target longer than --max-uri-bytes"},
    {ProblemType::UnsupportedEncoding, "a Content-Encoding other than identity"},
    {ProblemType::ExpectationFailed, "an Expect other than 100-continue"},
    {ProblemType::TooManyConnections,
     "this client already holds its share of connections: only /livez and /readyz are answered "
     "on this one"},
    {ProblemType::HeadersTooLarge, "too many header fields, or too many bytes of them"},
    {ProblemType::Internal,
     "a bug or an Embree failure (the request is logged), or an import's sandbox that could not "
     "start (fork failed)"},
    {ProblemType::Unavailable,
     "the server is starting (recovering its data directory) or shutting down, or holds more "
     "unfinished request data than --max-buffered-mb",
     "Retry-After"},
};

/// The response headers operations name (ResponseDoc::headers).
constexpr std::pair<const char*, const char*> HEADERS[] = {
    {"ETag", "The scene version the answer belongs to, as a strong entity tag: \"N\"."},
    {"Retry-After", "Seconds to wait before asking again."},
    {"Allow", "The methods the path serves."},
    {"WWW-Authenticate", "Bearer: the token scheme."},
    {"Cache-Control", "no-store: every frame is rendered for its request."},
    {"X-Strata-Rebuild",
     "One line summing up the commit the render ran: v12 tlas=update(19) rebuilds=1 refits=0 "
     "prims=4096 ms=1.250."},
    {"X-Strata-Report",
     "The rebuild report of the render's commit, as compact JSON of at most 3 KiB: a longer one "
     "keeps its counts, lists only its first entries and says `entries_truncated: true`."},
    {"X-Strata-Samples", "Samples per pixel the frame holds (grows while accumulating)."},
    {"X-Strata-Split", "Who rendered each band of a split frame."},
    {"Content-Disposition", "attachment; filename=\"scene-N.strata\"."},
};

const char* BEARER_DOC =
    "With a token (--token-file, STRATA_TOKEN_FILE or STRATA_TOKEN), every endpoint but /livez, "
    "/readyz, / and /web/... needs `Authorization: Bearer <token>` (401 otherwise); a server "
    "started without one (loopback, or STRATA_INSECURE=1) needs none.";

J schema_ref(const std::string& name) {
    STRATA_CHECK(component_schemas().contains(name));
    return {{"$ref", "#/components/schemas/" + name}};
}

J parse_schema(const std::string& text) {
    J j = J::parse(text, nullptr, /*allow_exceptions=*/false);
    STRATA_CHECK(j.is_object());
    return j;
}

/// "{id}" -> "id", "{path...}" -> "path"; "" for a literal segment.
std::string parameter_name(std::string_view segment) {
    if (segment.size() < 3 || segment.front() != '{' || segment.back() != '}') return "";
    std::string_view name = segment.substr(1, segment.size() - 2);
    if (name.ends_with("...")) name.remove_suffix(3);
    return std::string(name);
}

std::vector<std::string> split_segments(std::string_view pattern) {
    std::vector<std::string> out;
    std::size_t start = 1;
    while (start <= pattern.size()) {
        const std::size_t slash = std::min(pattern.find('/', start), pattern.size());
        out.emplace_back(pattern.substr(start, slash - start));
        start = slash + 1;
    }
    return out;
}

/// The OpenAPI path of a route pattern: a rest parameter "{path...}" becomes "{path}".
std::string openapi_path(std::string_view pattern) {
    std::string out;
    for (const std::string& segment : split_segments(pattern)) {
        const std::string name = parameter_name(segment);
        out += "/" + (name.empty() ? segment : "{" + name + "}");
    }
    return out;
}

std::string operation_id(const std::string& method, std::string_view pattern) {
    std::string id;
    for (char c : pattern) {
        const bool word = std::isalnum(static_cast<unsigned char>(c));
        if (word)
            id += c;
        else if (!id.empty() && id.back() != '_')
            id += '_';
    }
    while (!id.empty() && id.back() == '_') id.pop_back();
    std::string m = method;
    for (char& c : m) c = char(std::tolower(static_cast<unsigned char>(c)));
    return m + "_" + (id.empty() ? "root" : id);
}

J parameter_json(const ParamDoc& p) {
    J j = {{"name", p.name}, {"in", p.in}};
    if (!p.description.empty()) j["description"] = p.description;
    if (p.required || p.in == "path") j["required"] = true;
    j["schema"] = parse_schema(p.schema);
    if (p.comma_separated) {
        j["style"] = "form";
        j["explode"] = false;
    }
    return j;
}

/// The route's own parameters, then a path parameter for each of the pattern's the doc leaves
/// undescribed.
J parameters_json(std::string_view pattern, const RouteDoc& doc) {
    J out = J::array();
    for (const ParamDoc& p : doc.parameters) out.push_back(parameter_json(p));
    for (const std::string& segment : split_segments(pattern)) {
        const std::string name = parameter_name(segment);
        const bool described = std::any_of(doc.parameters.begin(), doc.parameters.end(),
                                           [&](const ParamDoc& p) { return p.name == name; });
        if (name.empty() || described) continue;
        const bool rest = segment.ends_with("...}");
        out.push_back(parameter_json(
            {.name = name,
             .in = "path",
             .description = rest ? "the rest of the path, slashes included"
                                 : "one path segment, percent-encoded (an id holding '/' is "
                                   "sent as %2F)"}));
    }
    return out;
}

J request_body_json(const RouteDoc& doc) {
    J content = J::object();
    if (!doc.body.empty()) content["application/json"] = {{"schema", schema_ref(doc.body)}};
    for (const std::string& media : doc.body_media) content[media] = J::object();
    return {{"required", doc.body_required}, {"content", std::move(content)}};
}

/// One status's answer; problems of one status share it (their descriptions joined).
struct Answer {
    std::vector<std::string> descriptions;
    std::string schema;
    std::vector<std::string> media;
    std::vector<std::string> headers;
};

void add_answer(std::map<int, Answer>& answers, const ResponseDoc& r) {
    Answer& a = answers[r.status];
    if (std::find(a.descriptions.begin(), a.descriptions.end(), r.description) ==
        a.descriptions.end())
        a.descriptions.push_back(r.description);
    if (!r.schema.empty()) a.schema = r.schema;
    for (const std::string& m : r.media)
        if (std::find(a.media.begin(), a.media.end(), m) == a.media.end()) a.media.push_back(m);
    for (const std::string& h : r.headers)
        if (std::find(a.headers.begin(), a.headers.end(), h) == a.headers.end())
            a.headers.push_back(h);
}

J answer_json(const Answer& a) {
    std::string description;
    for (const std::string& d : a.descriptions)
        description += (description.empty() ? "" : "; ") + d;
    J j = {{"description", description}};
    if (!a.headers.empty()) {
        J headers = J::object();
        for (const std::string& h : a.headers) {
            STRATA_CHECK(std::any_of(std::begin(HEADERS), std::end(HEADERS),
                                     [&](const auto& known) { return h == known.first; }));
            headers[h] = {{"$ref", "#/components/headers/" + h}};
        }
        j["headers"] = std::move(headers);
    }
    J content = J::object();
    if (!a.schema.empty()) {
        const std::string media = a.media.empty() ? "application/json" : a.media.front();
        content[media] = {{"schema", schema_ref(a.schema)}};
    } else {
        for (const std::string& m : a.media) content[m] = J::object();
    }
    if (!content.empty()) j["content"] = std::move(content);
    return j;
}

ResponseDoc refusal_doc(const Refusal& r) {
    std::vector<std::string> headers;
    if (r.header) headers.emplace_back(r.header);
    return problem(problem_status(r.type), r.when, std::move(headers));
}

/// A refusal's name in components/responses: its problem type's slug.
std::string refusal_name(const Refusal& r) {
    const std::string uri = problem_type_uri(r.type);
    return uri.substr(uri.rfind('/') + 1);
}

/// The route's answers, then the front end's refusals (401 only where a token is needed).
J responses_json(const RouteDoc& doc) {
    std::map<int, Answer> answers;
    for (const ResponseDoc& r : doc.responses) add_answer(answers, r);
    std::map<int, std::string> shared;  // status -> components/responses name
    for (const Refusal& r : FRONT_END_REFUSALS) {
        if (doc.open && (r.type == ProblemType::Unauthorized || r.type == ProblemType::Forbidden))
            continue;
        const int status = problem_status(r.type);
        if (answers.count(status))
            add_answer(answers, refusal_doc(r));
        else
            shared[status] = refusal_name(r);
    }
    std::map<int, J> out;
    for (const auto& [status, answer] : answers) out[status] = answer_json(answer);
    for (const auto& [status, name] : shared)
        out[status] = {{"$ref", "#/components/responses/" + name}};
    J responses = J::object();
    for (auto& [status, answer] : out) responses[std::to_string(status)] = std::move(answer);
    return responses;
}

J operation_json(const RouteListing& route) {
    const RouteDoc& doc = *route.doc;
    J op = {{"operationId", operation_id(route.method, route.pattern)}};
    if (!doc.tag.empty()) op["tags"] = {doc.tag};
    op["summary"] = doc.summary;
    if (!doc.description.empty()) op["description"] = doc.description;
    const J parameters = parameters_json(route.pattern, doc);
    if (!parameters.empty()) op["parameters"] = parameters;
    if (!doc.body.empty() || !doc.body_media.empty()) op["requestBody"] = request_body_json(doc);
    op["responses"] = responses_json(doc);
    if (doc.open)
        op["security"] = J::array();
    else if (doc.query_token)
        op["security"] = J::array({{{"bearer", J::array()}}, {{"access_token", J::array()}}});
    return op;
}

J paths_json(const std::vector<RouteListing>& routes) {
    J paths = J::object();
    for (const RouteListing& route : routes) {
        const std::string path = openapi_path(route.pattern);
        J& item = paths[path];
        // The route table's own pattern, where OpenAPI cannot say it: a rest parameter.
        if (path != route.pattern) item["x-strata-pattern"] = route.pattern;
        std::string method = route.method;
        for (char& c : method) c = char(std::tolower(static_cast<unsigned char>(c)));
        STRATA_CHECK(!item.contains(method));
        item[method] = operation_json(route);
    }
    return paths;
}

J components_json() {
    J headers = J::object();
    for (const auto& [name, description] : HEADERS)
        headers[name] = {{"description", description}, {"schema", {{"type", "string"}}}};
    const J security = {
        {"bearer", {{"type", "http"}, {"scheme", "bearer"}, {"description", BEARER_DOC}}},
        {"access_token",
         {{"type", "apiKey"},
          {"in", "query"},
          {"name", "access_token"},
          {"description",
           "The token as a query parameter (RFC 6750 2.3), for browsers' <img> and "
           "EventSource, which cannot send Authorization: GET /v1/stream, /v1/events and "
           "/v1/render only. Prefer the header."}}}};
    J refusals = J::object();
    for (const Refusal& r : FRONT_END_REFUSALS) {
        std::map<int, Answer> one;
        add_answer(one, refusal_doc(r));
        refusals[refusal_name(r)] = answer_json(one.begin()->second);
    }
    return {{"schemas", component_schemas()},
            {"responses", std::move(refusals)},
            {"headers", std::move(headers)},
            {"securitySchemes", security}};
}

}  // namespace

ResponseDoc ok_json(std::string schema, std::string description, std::vector<std::string> headers) {
    return {.status = 200,
            .description = std::move(description),
            .schema = std::move(schema),
            .headers = std::move(headers)};
}

ResponseDoc problem(int status, std::string when, std::vector<std::string> headers) {
    return {.status = status,
            .description = std::move(when),
            .schema = "Problem",
            .media = {"application/problem+json"},
            .headers = std::move(headers)};
}

std::vector<ParamDoc> query_parameters(std::string_view schema,
                                       const std::vector<std::string>& leave_out) {
    const J& schemas = component_schemas();
    // A member's schema, through one $ref.
    const auto resolved = [&](const J& s) -> const J& {
        const std::string target = s.value("$ref", "");
        const std::string prefix = "#/components/schemas/";
        return target.starts_with(prefix) ? schemas.at(target.substr(prefix.size())) : s;
    };
    std::vector<ParamDoc> out;
    // A nested object's members are parameters of their own, named with the prefix its member
    // schema gives as x-query-prefix (frame's group is frame_group; camera's eye is eye).
    const auto add = [&](const J& object, const std::string& prefix, auto& self) -> void {
        const J required = object.value("required", J::array());
        for (const auto& [name, member] : object.at("properties").items()) {
            if (std::find(leave_out.begin(), leave_out.end(), name) != leave_out.end()) continue;
            const J& target = resolved(member);
            if (target.value("type", "") == "object") {
                self(target, prefix + member.value("x-query-prefix", ""), self);
                continue;
            }
            out.push_back(
                {.name = prefix + name,
                 .description = member.value("description", ""),
                 .schema = member.dump(),
                 .required = std::find(required.begin(), required.end(), name) != required.end(),
                 .comma_separated = target.value("type", "") == "array"});
        }
    };
    add(schemas.at(std::string(schema)), "", add);
    return out;
}

OrderedJson openapi_document(const std::vector<RouteListing>& routes, std::string_view version) {
    const J info = {
        {"title", "Strata"},
        {"version", version},
        {"summary", "A scene server: edit a scene over HTTP, render it, pick in it, stream it."},
        {"description",
         "Generated from strata-server's route table and the protocol's op, field and problem "
         "tables. protocol/README.md explains the behaviour behind each endpoint: versions and "
         "If-Match, the edit ops, rebuild reports, limits and durability."},
        {"license", {{"name", "Apache-2.0"}, {"identifier", "Apache-2.0"}}}};
    return {{"openapi", "3.1.0"},
            {"info", info},
            {"security", J::array({{{"bearer", J::array()}}})},
            {"paths", paths_json(routes)},
            {"components", components_json()}};
}

}  // namespace strata::protocol

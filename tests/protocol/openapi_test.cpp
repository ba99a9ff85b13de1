// The OpenAPI generator on a small route list: paths and parameters from patterns, security from
// the docs, the front end's refusals on every operation, every reference resolvable, and the
// components built from the protocol's tables (problem types, field tables, counters).

#include <set>
#include <string>

#include <gtest/gtest.h>

#include "engine/counters.h"
#include "protocol/field_json.h"
#include "protocol/openapi.h"
#include "protocol/problem.h"

namespace strata::protocol {
namespace {

const RouteDoc OBJECT = {.summary = "one mesh",
                         .responses = {ok_json("Mesh", "it"), problem(404, "no such mesh")}};
const RouteDoc FILES = {
    .summary = "files",
    .responses = {{.status = 200, .description = "a file", .media = {"text/html"}}},
    .open = true};
const RouteDoc EDITS = {.summary = "edits",
                        .body = "EditBatch",
                        .body_required = true,
                        .responses = {ok_json("EditResult", "applied")}};
const RouteDoc STREAM = {
    .summary = "frames",
    .parameters = query_parameters("RenderRequest"),
    .responses = {{.status = 200, .description = "frames", .media = {"multipart/x-mixed-replace"}}},
    .query_token = true};

OrderedJson sample_document() {
    return openapi_document({{"GET", "/v1/scene/meshes/{id}", &OBJECT},
                             {"GET", "/web/{path...}", &FILES},
                             {"POST", "/v1/edits", &EDITS},
                             {"GET", "/v1/stream", &STREAM}},
                            "1.2.3");
}

/// Every "$ref" string under `j`.
void collect_refs(const OrderedJson& j, std::set<std::string>& out) {
    if (j.is_object()) {
        for (const auto& [key, value] : j.items()) {
            if (key == "$ref" && value.is_string())
                out.insert(value.get<std::string>());
            else
                collect_refs(value, out);
        }
    } else if (j.is_array()) {
        for (const OrderedJson& e : j) collect_refs(e, out);
    }
}

TEST(OpenApi, EveryReferenceResolvesInsideTheDocument) {
    const OrderedJson doc = sample_document();
    std::set<std::string> refs;
    collect_refs(doc, refs);
    EXPECT_GT(refs.size(), 20u);
    for (const std::string& ref : refs) {
        ASSERT_TRUE(ref.starts_with("#/")) << ref;
        EXPECT_TRUE(doc.contains(OrderedJson::json_pointer(ref.substr(1)))) << ref;
    }
    EXPECT_EQ(doc["openapi"], "3.1.0");
    EXPECT_EQ(doc["info"]["version"], "1.2.3");
}

TEST(OpenApi, PatternsBecomePathsWithTheirParameters) {
    const OrderedJson paths = sample_document()["paths"];
    const OrderedJson& get = paths["/v1/scene/meshes/{id}"]["get"];
    ASSERT_EQ(get["parameters"].size(), 1u);
    EXPECT_EQ(get["parameters"][0]["name"], "id");
    EXPECT_EQ(get["parameters"][0]["in"], "path");
    EXPECT_EQ(get["parameters"][0]["required"], true);
    // A rest parameter keeps the table's pattern beside the path OpenAPI can say.
    ASSERT_TRUE(paths.contains("/web/{path}"));
    EXPECT_EQ(paths["/web/{path}"]["x-strata-pattern"], "/web/{path...}");
    EXPECT_EQ(
        paths["/v1/edits"]["post"]["requestBody"]["content"]["application/json"]["schema"]["$ref"],
        "#/components/schemas/EditBatch");
}

TEST(OpenApi, OpenRoutesNeedNoTokenAndQueryTokenRoutesTakeEither) {
    const OrderedJson doc = sample_document();
    EXPECT_EQ(doc["security"][0].begin().key(), "bearer");
    const OrderedJson& files = doc["paths"]["/web/{path}"]["get"];
    EXPECT_EQ(files["security"], OrderedJson::array());
    EXPECT_FALSE(files["responses"].contains("401"));
    const OrderedJson& object = doc["paths"]["/v1/scene/meshes/{id}"]["get"];
    EXPECT_FALSE(object.contains("security")) << "the document's default: the bearer token";
    EXPECT_TRUE(object["responses"].contains("401"));
    EXPECT_EQ(doc["paths"]["/v1/stream"]["get"]["security"].size(), 2u);
}

TEST(OpenApi, EveryOperationListsTheFrontEndsRefusalsAsProblems) {
    const OrderedJson doc = sample_document();
    const OrderedJson& responses = doc["paths"]["/v1/edits"]["post"]["responses"];
    for (const char* status :
         {"400", "401", "408", "413", "414", "415", "417", "429", "431", "500", "503"}) {
        ASSERT_TRUE(responses.contains(status)) << status;
        OrderedJson answer = responses[status];
        // A status the route says nothing of refers to the shared refusal.
        if (answer.contains("$ref"))
            answer = doc.at(OrderedJson::json_pointer(answer["$ref"].get<std::string>().substr(1)));
        EXPECT_EQ(answer["content"]["application/problem+json"]["schema"]["$ref"],
                  "#/components/schemas/Problem")
            << status;
    }
    EXPECT_EQ(responses["408"]["$ref"], "#/components/responses/request-timeout");
    EXPECT_EQ(doc["components"]["responses"]["unavailable"]["headers"].begin().key(),
              "Retry-After");
}

TEST(OpenApi, TheProblemSchemaNamesEveryProblemTypeWithItsTitleAndStatus) {
    const OrderedJson& problem_schema = component_schemas()["Problem"];
    const OrderedJson& uris = problem_schema["properties"]["type"]["enum"];
    const OrderedJson& cases = problem_schema["allOf"];
    ASSERT_EQ(uris.size(), std::size_t(ProblemType::Internal) + 1);
    ASSERT_EQ(cases.size(), uris.size());
    const auto t = ProblemType::VersionMismatch;
    const OrderedJson& c = cases[std::size_t(t)];
    EXPECT_EQ(c["if"]["properties"]["type"]["const"], problem_type_uri(t));
    EXPECT_EQ(c["then"]["properties"]["status"]["const"], 412);
    EXPECT_EQ(c["then"]["properties"]["title"]["const"], problem_title(t));
}

TEST(OpenApi, ObjectDocumentsHoldEveryFieldOfTheirKindsTable) {
    const OrderedJson& instance = component_schemas()["Instance"];
    for_each_field<InstanceFields>([&](const auto& row) {
        const std::string name(row.info.name);
        EXPECT_TRUE(instance["properties"].contains(name)) << name;
        EXPECT_EQ(instance["properties"][name]["description"], row.info.doc) << name;
    });
    // The schemas the edit batch shares are components too, referenced where they were $defs.
    EXPECT_EQ(instance["properties"]["transform"]["$ref"], "#/components/schemas/transform");
    EXPECT_EQ(instance["additionalProperties"], false);
}

TEST(OpenApi, StatsCountersComeFromTheCounterTable) {
    const OrderedJson& counters = component_schemas()["Stats"]["properties"]["counters"];
    EXPECT_EQ(counters["properties"].size(), std::size(ENGINE_COUNTERS));
    for (const CounterSpec& c : ENGINE_COUNTERS)
        EXPECT_EQ(counters["properties"][std::string(c.name)]["description"], c.help);
}

TEST(OpenApi, QueryParametersStandForTheBodysMembersWithTheCameraFlattened) {
    std::set<std::string> names;
    for (const ParamDoc& p : query_parameters("RenderRequest", {"split"})) {
        names.insert(p.name);
        const bool list = p.name == "aovs" || p.name == "eye" || p.name == "target" ||
                          p.name == "up" || p.name == "band";
        EXPECT_EQ(p.comma_separated, list) << p.name;
    }
    for (const char* want :
         {"width", "height", "format", "aovs", "eye", "target", "up", "fov_y_deg", "band"})
        EXPECT_TRUE(names.count(want)) << want;
    EXPECT_FALSE(names.count("camera"));
    EXPECT_FALSE(names.count("split"));
}

}  // namespace
}  // namespace strata::protocol

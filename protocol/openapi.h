#pragma once
// The OpenAPI 3.1 description of the HTTP API (GET /v1/openapi.json), generated. The server hands
// over its route table as plain data (method, pattern and the RouteDoc each route was registered
// with); the schemas come from the tables the protocol already has: the edit-batch schema (the op
// table), the object kinds' field tables, the problem types, the statistics tables
// (openapi_schemas.cpp). Nothing here knows the server's types.
//
// The document is checked four ways: an OpenAPI 3.1 validator lints it (tests/protocol,
// check_openapi.py); every answer the HTTP suites get is validated against it (the process suites
// and Python clients as it arrives, tests/python/strata_process.py; the in-process C++ suites from
// a record, tests/server/check_answers.py); the JSON answers protocol/README.md shows are too
// (tests/protocol/check_readme_answers.py); and tests/protocol/openapi_test.cpp checks that every
// reference resolves.

#include <string>
#include <string_view>
#include <vector>

#include "protocol/edit_schema.h"

namespace strata::protocol {

/// One parameter of a route: in the query, the path or a header.
struct ParamDoc {
    std::string name = {};
    std::string in = "query";  ///< query, path or header
    std::string description = {};
    std::string schema = R"({"type": "string"})";  ///< its JSON Schema, as JSON text
    bool required = false;
    /// Arrays in the query: comma-separated (OpenAPI's form style without explode).
    bool comma_separated = false;
};

/// One answer of a route.
struct ResponseDoc {
    int status = 200;
    std::string description = {};
    /// The components/schemas name of its JSON body; "" when the body is not JSON.
    std::string schema = {};
    /// The media types of a body that is not JSON (image/png, ...); with `schema`: "" means
    /// application/json, a problem's is application/problem+json.
    std::vector<std::string> media = {};
    /// The components/headers it carries (ETag, Retry-After, ...).
    std::vector<std::string> headers = {};
};

/// What a route says about itself, given where it is registered (server/routes.cpp).
struct RouteDoc {
    std::string summary = {};
    std::string description = {};
    std::string tag = {};  ///< the group it is listed under (edits, scene, render, ...)
    std::vector<ParamDoc> parameters = {};
    /// The components/schemas name of a JSON request body, or the media types of another.
    std::string body = {};
    std::vector<std::string> body_media = {};
    bool body_required = false;
    std::vector<ResponseDoc> responses = {};
    bool open = false;         ///< answered without a token (the viewer's files, health checks)
    bool query_token = false;  ///< also takes the token as ?access_token= (browsers' <img>, ...)
};

/// One route of the table as the generator reads it.
struct RouteListing {
    std::string method = {};   ///< GET or POST
    std::string pattern = {};  ///< "/v1/scene/meshes/{id}", "/web/{path...}"
    const RouteDoc* doc = {};
};

/// 200 with a JSON body of components/schemas `schema` and an ETag (the scene version).
ResponseDoc ok_json(std::string schema, std::string description,
                    std::vector<std::string> headers = {"ETag"});
/// A problem answer (application/problem+json) of `status`, and when it is given.
ResponseDoc problem(int status, std::string when, std::vector<std::string> headers = {});

/// The query parameters that stand for the members of components/schemas `schema` (an object):
/// each member a parameter with its schema, arrays comma-separated, the members of `camera`
/// parameters of their own; `leave_out` names members that are not parameters.
std::vector<ParamDoc> query_parameters(std::string_view schema,
                                       const std::vector<std::string>& leave_out = {});

/// Every schema the description's components hold, by name: the edit batch and its definitions,
/// the problem document, reports, scene documents, pages and the rest (openapi_schemas.cpp).
const OrderedJson& component_schemas();

/// The whole OpenAPI 3.1 document of `routes`; `version` is the server's.
OrderedJson openapi_document(const std::vector<RouteListing>& routes, std::string_view version);

}  // namespace strata::protocol

// GET / and GET /web/<file>: the live viewer (clients/web), served from the bytes compiled into
// the binary (web_assets.h). Open without a token (request_reader.h, is_public_path): the files
// hold no scene data; the page asks for the token and sends it with each request it makes.

#include <algorithm>

#include "server/context.h"
#include "server/http_util.h"
#include "server/request_target.h"
#include "server/router.h"
#include "server/web_assets.h"

namespace strata::server {

namespace {

const char* content_type_of(std::string_view path) {
    const auto ends = [&](std::string_view ext) {
        return path.size() >= ext.size() && path.substr(path.size() - ext.size()) == ext;
    };
    if (ends(".html")) return "text/html; charset=utf-8";
    if (ends(".js")) return "text/javascript; charset=utf-8";
    if (ends(".css")) return "text/css; charset=utf-8";
    if (ends(".svg")) return "image/svg+xml";
    if (ends(".png")) return "image/png";
    if (ends(".json")) return "application/json";
    return "application/octet-stream";
}

void serve(httplib::Response& res, const std::string& path) {
    const auto& assets = web_assets();
    const auto it = std::find_if(assets.begin(), assets.end(),
                                 [&](const WebAsset& a) { return a.path == path; });
    if (it == assets.end())
        return send_problem(res, protocol::make_problem(protocol::ProblemType::NotFound,
                                                        "the viewer has no file '" + path + "'"));
    res.status = 200;
    // The files change with the binary only: revalidating is cheap, and a new build is seen.
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_content(std::string(it->bytes), content_type_of(path));
}

}  // namespace

void add_web_routes(Router& router) {
    router.get("/",
               [](const httplib::Request&, httplib::Response& res) { serve(res, "index.html"); });
    router.get("/web/(.+)", [](const httplib::Request& req, httplib::Response& res) {
        serve(res, decode_path_segment(req.matches[1].str()));
    });
}

}  // namespace strata::server

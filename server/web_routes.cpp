// GET / and GET /web/<file>: the live viewer (clients/web), served from the bytes compiled into
// the binary (web_assets.h). Open without a token (request_reader.h, is_public_path): the files
// hold no scene data; the page asks for the token and sends it with each request it makes.

#include <algorithm>

#include "server/context.h"
#include "server/route_table.h"
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

Reply serve(const std::string& path) {
    const auto& assets = web_assets();
    const auto it = std::find_if(assets.begin(), assets.end(),
                                 [&](const WebAsset& a) { return a.path == path; });
    if (it == assets.end())
        return protocol::make_problem(protocol::ProblemType::NotFound,
                                      "the viewer has no file '" + path + "'");
    protocol::ApiResponse r;
    r.content_type = content_type_of(path);
    // The files change with the binary only: revalidating is cheap, and a new build is seen.
    r.headers = {{"Cache-Control", "no-cache"}, {"X-Content-Type-Options", "nosniff"}};
    r.body = std::string(it->bytes);
    return r;
}

}  // namespace

void add_web_routes(RouteTable& routes) {
    const protocol::ResponseDoc missing = protocol::problem(404, "the viewer has no such file");
    routes.get("/",
               {{.summary = "The live viewer",
                 .tag = "viewer",
                 .responses = {{.status = 200, .description = "its page", .media = {"text/html"}},
                               missing},
                 .open = true},
                [](RouteCall&) { return serve("index.html"); }});
    routes.get(
        "/web/{path...}",
        {{.summary = "The viewer's files",
          .tag = "viewer",
          .responses = {{.status = 200,
                         .description = "the file",
                         .media = {"text/javascript", "text/css", "text/html", "image/svg+xml",
                                   "image/png", "application/json", "application/octet-stream"}},
                        missing},
          .open = true},
         [](RouteCall& call) { return serve(call.params[0]); }});
}

}  // namespace strata::server

// libFuzzer target for the HTTP-facing layer: bytes as a client sends them (request line,
// headers, framing, target, query, body; pipelined or not, in any segmentation) through the
// front end's request reader and the application's routes to protocol/api.h and the engine.
//
// Input: byte 0 picks the situation (token required, draining, over a connection limit, tokens
// with roles per scene) and the size of the segments the rest arrives in; the rest is what the
// client sends. Named scenes made by one input are deleted before the next.
//
// Checks, besides "no crash, no sanitizer report":
//   - every answer is one complete HTTP/1.1 response whose Content-Length is its body's length;
//   - never a 500: whatever a client sends is its own fault or fine;
//   - every JSON body is valid UTF-8 and valid JSON.
// Build and run: scripts/run-fuzz.sh.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <spdlog/spdlog.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "protocol/safe_text.h"
#include "server/application.h"
#include "server/auth.h"
#include "server/named_scenes.h"
#include "server/request_reader.h"

namespace {

using namespace strata;
using namespace strata::server;

#define FUZZ_CHECK(expr, text)                                                               \
    do {                                                                                     \
        if (!(expr)) {                                                                       \
            std::fprintf(stderr, "fuzz check failed: %s (line %d)\n%.*s\n", #expr, __LINE__, \
                         int(std::min<std::size_t>((text).size(), 2000)), (text).data());    \
            std::abort();                                                                    \
        }                                                                                    \
    } while (false)

struct World {
    ServerConfig config;
    std::unique_ptr<Engine> engine;
    ServerMetrics metrics;
    std::unique_ptr<Application> app;
    ReaderConfig open_reader;
    ReaderConfig token_reader;
    ReaderConfig tokens_reader;  ///< --tokens-file: roles per scene

    World() {
        spdlog::set_level(spdlog::level::off);
        // Small limits keep every input fast: renders of at most 16x16 that stop after a
        // second, a scene budget of 200k triangles and 4096 instances, 64 KiB bodies.
        config.max_pixels = 256;
        config.max_scene_instances = 4096;
        config.render_timeout_s = 1;
        config.max_body_bytes = 64 << 10;
        // Named scenes get the same small budget, and at most four of them.
        config.max_scene_triangles = 200000;
        config.max_scene_vertices = 200000;
        config.max_scenes = 4;
        EngineConfig ec;
        ec.budget = {200000, 200000, uint64_t(256) << 20, 4096};
        engine = std::move(Engine::create(ec).value());
        app = std::make_unique<Application>(config, *engine, metrics, nullptr);
        open_reader.limits.max_body_bytes = config.max_body_bytes;
        token_reader = open_reader;
        token_reader.token = "fuzz";
        tokens_reader = open_reader;
        tokens_reader.tokens = std::make_shared<const TokenTable>(
            parse_token_table("fuzz a:admin b:read default:read\nfuzzer *:edit\n", "fuzz").value());
    }

    /// The same small scene before every input, so that a crash reproduces from its input alone.
    void reset() {
        EditBatch b;
        b.edits.emplace_back(Clear{});
        b.edits.emplace_back(add_mesh_edit("box", make_box(Vec3(1.0f))));
        AddMaterial m;
        m.id = "red";
        b.edits.emplace_back(m);
        AddInstance i;
        i.id = "b";
        i.mesh = "box";
        b.edits.emplace_back(i);
        (void)engine->apply(std::move(b));
        // No named scene: each is destroyed as its last reference (this list) goes.
        std::vector<std::shared_ptr<HostedScene>> named = app->scenes().list();
        for (const auto& scene : named) app->scenes().remove(scene->name());
    }
};

/// Checks one response; returns its status.
int check_response(const std::string& r, bool head) {
    FUZZ_CHECK(r.rfind("HTTP/1.1 ", 0) == 0 && r.size() > 12, r);
    const int status = std::atoi(r.c_str() + 9);
    FUZZ_CHECK(status >= 100 && status < 600 && status != 500, r);
    const std::size_t end = r.find("\r\n\r\n");
    FUZZ_CHECK(end != std::string::npos, r);
    const std::string_view fields(r.data(), end);
    const std::size_t cl = fields.find("\r\nContent-Length: ");
    FUZZ_CHECK(cl != std::string_view::npos, r);
    const std::size_t length = std::strtoull(r.c_str() + cl + 18, nullptr, 10);
    const std::string_view body = std::string_view(r).substr(end + 4);
    FUZZ_CHECK(body.size() == (head ? 0 : length), r);
    if (!head && fields.find("Content-Type: application/") != std::string_view::npos &&
        fields.find("json") != std::string_view::npos &&
        fields.find("gzip") == std::string_view::npos) {
        FUZZ_CHECK(strata::protocol::is_valid_utf8(body), r);
        FUZZ_CHECK(strata::protocol::Json::accept(body), r);
    }
    return status;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static World world;
    if (size == 0) return 0;
    world.reset();
    const uint8_t mode = data[0];
    const std::string_view input(reinterpret_cast<const char*>(data) + 1, size - 1);
    const ReaderSituation situation{(mode & 0x02) != 0, (mode & 0x04) != 0};
    const std::size_t segment = std::size_t(1) << ((mode >> 4) & 0x0F);  // 1 byte to 32 KiB
    RequestReader reader((mode & 0x08)   ? world.tokens_reader
                         : (mode & 0x01) ? world.token_reader
                                         : world.open_reader);

    std::size_t fed = 0;
    for (int steps = 0; steps < 64; ++steps) {
        ReaderStep step = reader.next(situation);
        if (step.kind == ReaderStep::Kind::NeedMore) {
            if (fed >= input.size()) break;
            const std::size_t n = std::min(segment, input.size() - fed);
            reader.append(input.data() + fed, n);
            fed += n;
        } else if (step.kind == ReaderStep::Kind::Answer) {
            check_response(step.answer.bytes, step.answer.method == "HEAD");
            if (step.answer.close) break;
        } else if (step.kind == ReaderStep::Kind::Request) {
            CancelToken cancel;
            RequestContext context;
            context.cancel = &cancel;
            const bool head = step.request.http.method == "HEAD";
            const bool close = !step.request.keep_alive;
            const Outcome outcome = world.app->handle(std::move(step.request), context, close);
            check_response(outcome.bytes, head);
        }
    }
    return 0;
}

// GET and POST /v1/scene/snapshot: a scene moved between servers, or kept in version control, as
// the same file format the data directory's snapshots use.

#include <cstring>

#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "protocol/api.h"

namespace strata::protocol {

ApiResponse get_snapshot(const Engine& engine) {
    // The copy-on-write image is taken under the read lock (microseconds); the batch is built
    // and encoded after it is released.
    const SceneImage image = engine.read([](const Scene& s) { return s.image(); });
    const uint64_t version = image.version;
    ApiResponse r;
    r.status = 200;
    r.content_type = SNAPSHOT_CONTENT_TYPE;
    r.body = durable::encode_snapshot(image.to_batch(), version);
    r.headers = {{"ETag", etag(version)},
                 {"Content-Disposition",
                  "attachment; filename=\"scene-" + std::to_string(version) + ".strata\""}};
    return r;
}

ApiResponse post_snapshot(Engine& engine, std::string body,
                          std::optional<std::string_view> if_match, const BatchApply* apply,
                          std::size_t max_edits) {
    Problem problem;
    const auto condition = if_match ? parse_if_match(*if_match, problem) : IfMatch{};
    if (!condition) return problem_response(problem);
    // The payload starts with its edit count (engine/durable/edit_codec.h): a snapshot of too
    // many edits is refused before one is decoded.
    if (auto view = durable::open_snapshot(body)) {
        if (const uint32_t count = durable::edit_count(view->payload); count > max_edits)
            return problem_response(make_problem(
                ProblemType::TooLarge, "the snapshot holds " + std::to_string(count) +
                                           " edits, more than " + std::to_string(max_edits) +
                                           " (--max-batch-edits): the scene was not loaded"));
    }
    auto snapshot = durable::decode_snapshot(body);
    body = {};
    if (!snapshot)
        return problem_response(
            make_problem(ProblemType::InvalidRequest,
                         "the body is not a valid Strata snapshot: " + snapshot.error().message));
    // One batch: everything goes, then the snapshot's scene comes; all or nothing.
    EditBatch batch;
    batch.edits.reserve(snapshot->scene.edits.size() + 1);
    batch.edits.emplace_back(Clear{});
    for (Edit& e : snapshot->scene.edits) batch.edits.push_back(std::move(e));
    snapshot->scene.edits.clear();
    auto applied = apply ? (*apply)(std::move(batch), condition->version)
                         : engine.apply(std::move(batch), condition->version);
    if (!applied) {
        const Error& e = applied.error();
        if (e.code == ErrorCode::VersionMismatch) {
            ApiResponse r = problem_response(
                make_problem(ProblemType::VersionMismatch, "If-Match: " + e.message));
            r.headers.emplace_back("ETag",
                                   etag(engine.read([](const Scene& s) { return s.version(); })));
            return r;
        }
        Problem p = problem_from(e);
        p.detail = "the snapshot was not loaded (the scene is unchanged): " + p.detail;
        return problem_response(p);
    }
    const ApplyResult& done = applied.value();
    ApiResponse r = json_response(200, {{"version", done.version},
                                        {"applied", done.applied},
                                        {"snapshot_version", snapshot->version}});
    r.headers.emplace_back("ETag", etag(done.version));
    return r;
}

}  // namespace strata::protocol

#pragma once
// A Transport that records requests and answers like a tiny, predictable server: every batch
// moves the version by one; commits report the TLAS action queued for them ("none" by default);
// picks answer `pick_hit` for every pixel; listings page through `listed` two items at a time;
// the scene and stats documents are the canned ones a test sets.

#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "clients/cli/json.h"
#include "clients/cli/transport.h"

namespace strata::cli::test {

class FakeTransport final : public Transport {
public:
    Reply edits(std::string body, const std::optional<std::string>&) override {
        const Json doc = Json::parse(body);
        edit_bodies.push_back(doc);
        if (!refusal.body.empty()) return refusal;
        ++version;
        return json(200, {{"version", version}, {"applied", doc["edits"].size()}});
    }
    // Undo and history are tested against a real server (commands_test.cpp).
    Reply undo(bool, const std::optional<std::string>&) override { return json(501, {}); }
    Reply history(const std::multimap<std::string, std::string>&) override {
        return json(501, {});
    }
    Reply commit() override {
        ++commits;
        last = next_report(false);
        return json(200, last);
    }
    Reply plan() override { return json(200, next_report(true)); }
    Reply render(const std::string& body) override {
        render_bodies.push_back(Json::parse(body));
        last = next_report(false);
        Reply r;
        r.status = 200;
        r.content_type = "image/png";
        r.body = "frame at v" + std::to_string(version);
        r.headers = {{"ETag", "\"" + std::to_string(version) + "\""},
                     {"X-Strata-Report", last.dump()}};
        return r;
    }
    Reply stats() override {
        ++stats_calls;
        Json doc = {{"version", version}, {"last_report", last}};
        if (!memory_bytes.is_null()) doc["memory_bytes"] = memory_bytes;
        return json(200, doc);
    }
    Reply scene() override {
        return json(200, scene_doc.is_null() ? Json{{"version", version}} : scene_doc);
    }
    Reply scene_list(const std::string& collection,
                     const std::multimap<std::string, std::string>& query) override {
        list_queries.emplace_back(collection, query);
        const auto cursor = query.find("cursor");
        const std::size_t first = cursor == query.end() ? 0 : std::stoul(cursor->second);
        Json page = {{"version", version}, {"items", Json::array()}, {"next_cursor", nullptr}};
        for (std::size_t i = first; i < listed.size() && i < first + 2; ++i)
            page["items"].push_back({{"id", listed[i]}});
        if (first + 2 < listed.size()) page["next_cursor"] = std::to_string(first + 2);
        return json(200, page);
    }
    Reply scene_object(const std::string&, const std::string&) override { return {}; }
    Reply pick(const std::string& body) override {
        pick_bodies.push_back(Json::parse(body));
        Json hits = Json::array();
        for (std::size_t i = 0; i < pick_bodies.back()["pixels"].size(); ++i)
            hits.push_back(pick_hit);
        return json(200, {{"version", version}, {"hits", hits}});
    }
    Reply get_snapshot(std::optional<uint64_t>, const std::optional<std::string>&) override { return {200, "", "application/vnd.strata.snapshot", "SNAP", {}}; }
    Reply put_snapshot(std::string bytes) override {
        snapshot_posted = std::move(bytes);
        return json(200, {{"version", ++version}, {"applied", 1}});
    }
    Reply import_asset(std::string bytes,
                       const std::multimap<std::string, std::string>& query) override {
        asset_posted = std::move(bytes);
        asset_query = query;
        return json(200, {{"version", ++version}, {"applied", 2}, {"meshes", {"a.mesh0"}},
                          {"materials", Json::array()}, {"groups", {"a"}},
                          {"instances", {"a.node0"}},
                          {"warnings", Json::array()}});
    }
    // Assets: only over a real server (commands_test.cpp).
    Reply assets(const std::optional<std::string>&) override { return {}; }
    Reply delete_asset(const std::string&) override { return {}; }
    Reply put_asset(const std::string&, std::string,
                    const std::multimap<std::string, std::string>&) override {
        return {};
    }
    std::string describe() const override { return "the fake"; }
    std::string asset_posted;
    std::multimap<std::string, std::string> asset_query;
    std::string snapshot_posted;

    /// A 422 problem answer for every later edit batch.
    void refuse_edits() {
        refusal.status = 422;
        refusal.content_type = "application/problem+json";
        refusal.body = R"({"type": "https://strata.dev/problems/unknown-id", "title": "Unknown id",
            "status": 422, "detail": "edit 0 (/edits/0/mesh): unknown mesh 'rock'",
            "edit_index": 0, "pointer": "/edits/0/mesh"})";
    }

    uint64_t version = 0;
    int commits = 0;
    int stats_calls = 0;
    std::deque<std::string> tlas_actions;  ///< actions of the next reports, in order
    std::vector<Json> edit_bodies;
    std::vector<Json> render_bodies;
    std::vector<Json> pick_bodies;
    Json pick_hit = nullptr;          ///< what every picked pixel shows (null: nothing)
    std::vector<std::string> listed;  ///< the ids every listing answers
    std::vector<std::pair<std::string, std::multimap<std::string, std::string>>> list_queries;
    Json last;
    Json scene_doc = nullptr;     ///< what GET /v1/scene answers (null: just the version)
    Json memory_bytes = nullptr;  ///< the stats' memory_bytes (null: left out)
    Reply refusal;

private:
    Json next_report(bool planned) {
        std::string action = "none";
        if (!tlas_actions.empty()) {
            action = tlas_actions.front();
            tlas_actions.pop_front();
        }
        Json r = {{"version", version},
                  {"planned", planned},
                  {"tlas", {{"action", action}, {"instances", 1}}},
                  {"blas_rebuilds", 0},
                  {"blas_refits", 0},
                  {"rebuilt", Json::array()},
                  {"refit", Json::array()},
                  {"released", Json::array()},
                  {"primitives_built", 0},
                  {"primitives_refit", 0}};
        if (!planned) r["ms"] = 0.5;
        return r;
    }
    static Reply json(int status, const Json& body) {
        Reply r;
        r.status = status;
        r.content_type = "application/json";
        r.body = body.dump();
        r.headers = {{"Content-Type", r.content_type}};
        return r;
    }
};

}  // namespace strata::cli::test

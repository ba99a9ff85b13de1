// Throughput of the edit protocol: a 1M-vertex update_mesh as a plain JSON array and as base64,
// parsed alone and parsed, validated and applied; and a batch of 100k small edits of every
// kind, where per-op dispatch and member checks dominate. Run by hand (never by CTest):
//
//   build/tests/bench/strata_protocol_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true

#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include <benchmark/benchmark.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "protocol/base64.h"
#include "protocol/edit_parser.h"

namespace strata {
namespace {

constexpr uint32_t VERTICES = 1'000'000;

/// A plane with about VERTICES vertices (1000 x 999 quads -> 1001 * 1000 vertices).
MeshData big_plane() {
    return make_plane(Vec3(10.0f), 1000, 999);
}

std::string positions_json(const std::vector<Vec3>& positions) {
    std::string out = R"({"edits":[{"op":"update_mesh","mesh":"big","positions":[)";
    out.reserve(positions.size() * 3 * 12 + 64);
    char buf[32];
    for (std::size_t i = 0; i < positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            const int n = std::snprintf(buf, sizeof buf, "%.7g", double(positions[i][k]));
            if (i || k) out += ',';
            out.append(buf, std::size_t(n));
        }
    }
    out += "]}]}";
    return out;
}

std::string positions_b64_json(const std::vector<Vec3>& positions) {
    const std::string_view bytes(reinterpret_cast<const char*>(positions.data()),
                                 positions.size() * 12);
    return R"({"edits":[{"op":"update_mesh","mesh":"big","positions_b64":")" +
           protocol::encode_base64(bytes) + "\"}]}";
}

std::vector<Vec3> moved_positions() {
    std::vector<Vec3> p = big_plane().positions;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(-0.01f, 0.01f);
    for (Vec3& v : p) v.y = jitter(rng);
    return p;
}

void parse_only(benchmark::State& state, const std::string& text) {
    for (auto _ : state) {
        auto parsed = protocol::parse_edit_batch(text, {});
        if (!parsed) {
            state.SkipWithError(parsed.error().detail.c_str());
            break;
        }
        benchmark::DoNotOptimize(parsed);
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(text.size()));
    state.counters["body_MB"] = double(text.size()) / 1e6;
}

void parse_and_apply(benchmark::State& state, const std::string& text) {
    auto engine = std::move(Engine::create().value());
    MeshData plane = big_plane();
    EditBatch add;
    add.edits.emplace_back(
        AddMesh{"big", std::move(plane.positions), std::move(plane.triangles), {}, {}});
    if (!engine->apply(std::move(add)).has_value()) state.SkipWithError("add_mesh failed");
    for (auto _ : state) {
        auto parsed = protocol::parse_edit_batch(text, {});
        if (!parsed) {
            state.SkipWithError(parsed.error().detail.c_str());
            break;
        }
        auto applied = engine->apply(std::move(parsed.value().batch));
        if (!applied) {
            state.SkipWithError(applied.error().message.c_str());
            break;
        }
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(text.size()));
}

void BM_UpdateMesh1M_JsonArray_Parse(benchmark::State& state) {
    static const std::string text = positions_json(moved_positions());
    parse_only(state, text);
}
void BM_UpdateMesh1M_Base64_Parse(benchmark::State& state) {
    static const std::string text = positions_b64_json(moved_positions());
    parse_only(state, text);
}
void BM_UpdateMesh1M_JsonArray_ParseApply(benchmark::State& state) {
    static const std::string text = positions_json(moved_positions());
    parse_and_apply(state, text);
}
void BM_UpdateMesh1M_Base64_ParseApply(benchmark::State& state) {
    static const std::string text = positions_b64_json(moved_positions());
    parse_and_apply(state, text);
}
/// 100k small edits cycling through the instance, material, camera and dirty ops.
std::string small_edits_json() {
    std::string out = R"({"edits":[)";
    for (int i = 0; i < 100'000; ++i) {
        const std::string n = std::to_string(i);
        const std::string k = std::to_string(i % 7);
        out += i ? "," : "";
        switch (i % 6) {
            case 0:
                out += R"({"op":"set_transform","instance":"i)" + n +
                       R"(","transform":{"translate":[)" + k + R"(,0,1],"scale":2}})";
                break;
            case 1:
                out += R"({"op":"update_instance","instance":"i)" + n +
                       R"(","visible":true,"mask":)" + k + R"(,"user_id":3})";
                break;
            case 2:
                out += R"({"op":"update_material","material":"m)" + n +
                       R"(","roughness":0.5,"base_color":[)" + k + ",0,0]}";
                break;
            case 3:
                out += R"({"op":"add_instance","id":"i)" + n +
                       R"(","mesh":"m","material":"red","mask":)" + k + "}";
                break;
            case 4:
                out += R"({"op":"set_camera","eye":[)" + k + ",1," + n + R"(],"fov_y_deg":40})";
                break;
            default:
                out += R"({"op":"mark_dirty","target":{"mesh":"m)" + n + R"("},"action":"refit"})";
        }
    }
    return out + "]}";
}

void BM_SmallEdits100k_Parse(benchmark::State& state) {
    static const std::string text = small_edits_json();
    parse_only(state, text);
}
/// Baseline: nlohmann's own DOM parse of the same text, without conversion to engine structs.
void BM_UpdateMesh1M_JsonArray_NlohmannDom(benchmark::State& state) {
    static const std::string text = positions_json(moved_positions());
    for (auto _ : state) benchmark::DoNotOptimize(nlohmann::json::parse(text));
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(text.size()));
}

BENCHMARK(BM_UpdateMesh1M_JsonArray_NlohmannDom)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateMesh1M_JsonArray_Parse)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateMesh1M_Base64_Parse)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateMesh1M_JsonArray_ParseApply)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_UpdateMesh1M_Base64_ParseApply)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SmallEdits100k_Parse)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace strata

BENCHMARK_MAIN();

// Noise at a few samples per pixel, with and without the à-trous filter (engine/render/
// aov_filter.h): RMSE of the linear colour against a high-spp reference of the same scene, on
// the demo scene and on an imported model, and the filter's own cost. A plain program:
//
//   build/tests/bench/strata_filter_bench [WIDTH HEIGHT REFERENCE_SPP]   (200 150 1024)
//
// The reference is one launch of REFERENCE_SPP samples; its first samples are the ones the
// few-spp frames use (each pixel has one fixed sequence), a 1/REFERENCE_SPP share of it.
// The filter's cost is timed twice per scene: filter_frame alone on a 1-spp frame (the spatial
// noise estimate; with memory of its own and with a reused FilterScratch), and the median render
// time with the filter minus the one without at 4 spp (the measured per-pixel variance, the
// renderer's reused memory), each at WIDTHxHEIGHT and at 640x360.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "engine/engine.h"
#include "engine/render/aov_filter.h"
#include "engine/scene/demo_scene.h"
#include "engine/scene/shapes.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/import.h"

using namespace strata;

namespace {

Frame render(Engine& engine, uint32_t w, uint32_t h, uint32_t spp, bool filter) {
    RenderRequest r;
    r.width = w;
    r.height = h;
    r.spp = spp;
    r.format = ImageFormat::Exr;
    r.filter = filter;
    auto f = engine.render_frame(r);
    if (!f) {
        std::fprintf(stderr, "render: %s\n", f.error().describe().c_str());
        std::exit(1);
    }
    return std::move(f.value());
}

double rmse(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Vec3 d = a[i] - b[i];
        sum += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
    }
    return std::sqrt(sum / double(3 * a.size()));
}

/// RMSE as a display shows it: each channel compressed with c / (1 + c) first.
double display_rmse(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Vec3 d = a[i] / (1.0f + a[i]) - b[i] / (1.0f + b[i]);
        sum += double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
    }
    return std::sqrt(sum / double(3 * a.size()));
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// Median over 7 runs of filter_frame alone (with memory of its own, and with a FilterScratch
/// reused as the renderer does), and of a 4-spp render with the filter minus one without, at
/// w x h.
void time_filter(const char* name, Engine& engine, uint32_t w, uint32_t h) {
    RenderRequest r;
    r.width = w;
    r.height = h;
    r.format = ImageFormat::Exr;
    r.aovs = {Aov::Albedo, Aov::Normal, Aov::Depth};
    const Frame guides = engine.render_frame(r).value();
    const auto time_ms = [&](FilterScratch* scratch) {
        FrameBuffers copy = guides.buffers;
        const auto t0 = std::chrono::steady_clock::now();
        filter_frame(copy, {}, 1, {}, scratch);
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
            .count();
    };
    FilterScratch scratch;
    time_ms(&scratch);
    std::vector<double> own, reused, with, without;
    for (int i = 0; i < 7; ++i) {
        own.push_back(time_ms(nullptr));
        reused.push_back(time_ms(&scratch));
        with.push_back(render(engine, w, h, 4, true).info.render_ms);
        without.push_back(render(engine, w, h, 4, false).info.render_ms);
    }
    std::printf("%-14s %ux%u: filter alone (1 spp) median %.2f ms, %.2f ms reusing its memory; "
                "4-spp render %.2f ms filtered, %.2f ms plain (difference %.2f ms)\n",
                name, w, h, median(own), median(reused), median(with), median(without),
                median(with) - median(without));
}

void measure(const char* name, Engine& engine, uint32_t w, uint32_t h, uint32_t ref_spp) {
    const Frame reference = render(engine, w, h, ref_spp, false);
    for (uint32_t spp : {1u, 4u, 16u, 64u}) {
        const Frame plain = render(engine, w, h, spp, false);
        const Frame filtered = render(engine, w, h, spp, true);
        std::printf("%-14s %3u spp  rmse plain %.4f  filtered %.4f  (%.0f%%)\n", name, spp,
                    rmse(plain.buffers.color, reference.buffers.color),
                    rmse(filtered.buffers.color, reference.buffers.color),
                    100.0 * rmse(filtered.buffers.color, reference.buffers.color) /
                        rmse(plain.buffers.color, reference.buffers.color));
        const double dp = display_rmse(plain.buffers.color, reference.buffers.color);
        const double df = display_rmse(filtered.buffers.color, reference.buffers.color);
        std::printf("%-14s %3u spp  display rmse plain %.4f  filtered %.4f  (%.0f%%)\n", name,
                    spp, dp, df, 100.0 * df / dp);
    }
    if (std::getenv("STRATA_FILTER_BENCH_NO_TIMES")) return;
    time_filter(name, engine, w, h);
    time_filter(name, engine, 640, 360);
}

std::unique_ptr<Engine> engine_with(EditBatch batch) {
    auto engine = std::move(Engine::create().value());
    if (auto r = engine->apply(std::move(batch)); !r) {
        std::fprintf(stderr, "apply: %s\n", r.error().describe().c_str());
        std::exit(1);
    }
    return engine;
}

}  // namespace

int main(int argc, char** argv) {
    const uint32_t w = argc > 1 ? uint32_t(std::atoi(argv[1])) : 200;
    const uint32_t h = argc > 2 ? uint32_t(std::atoi(argv[2])) : 150;
    const uint32_t ref_spp = argc > 3 ? uint32_t(std::atoi(argv[3])) : 1024;

    auto demo = engine_with(make_demo_scene());
    measure("demo", *demo, w, h, ref_spp);

    const std::string path = std::string(STRATA_ASSIMP_MODELS_DIR) +
                             "/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    std::ifstream in(path, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), {}};
    auto asset = assets::import_asset(
        assets::AssetFormat::Glb,
        std::span(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), "engine", {});
    if (!asset) {
        std::fprintf(stderr, "%s: %s\n", path.c_str(), asset.error().detail.c_str());
        return 1;
    }
    assets::AssetBatch b = assets::asset_to_batch(std::move(asset.value()), {"engine", true});
    // The model on a ground plane, framed from its bounds like the reference-image tests.
    auto model = engine_with(std::move(b.batch));
    const Bounds3 box = model->read([](const Scene& s) { return s.world_bounds(); });
    const float size = glm::length(box.extent());
    EditBatch view;
    AddMesh ground =
        add_mesh_edit("ground", make_plane(Vec3(4.0f * size, 0, 4.0f * size), 1, 1), {});
    view.edits.emplace_back(std::move(ground));
    AddInstance g;
    g.id = "ground";
    g.mesh = "ground";
    g.transform = Affine::translation(Vec3(box.center().x, box.lower.y, box.center().z));
    view.edits.emplace_back(g);
    SetCamera cam;
    cam.target = box.center();
    cam.eye = box.center() + glm::normalize(Vec3(0.6f, 0.45f, 1.0f)) * (1.4f * size);
    cam.fov_y_deg = 40.0f;
    view.edits.emplace_back(cam);
    if (auto r = model->apply(std::move(view)); !r) {
        std::fprintf(stderr, "view: %s\n", r.error().describe().c_str());
        return 1;
    }
    measure("2CylinderEngine", *model, w, h, ref_spp);
    return 0;
}

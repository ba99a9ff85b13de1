// strata-demo: builds the demo scene, plays the demo edit sequence, prints each launch's rebuild
// report and writes one PNG frame per launch.
//
//   strata-demo [--out DIR] [--width W] [--height H] [--spp N] [--exposure EV] [--exr]
//   strata-demo --version

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "engine/engine.h"
#include "engine/scene/demo_scene.h"
#include "strata/version.h"

namespace {

struct Options {
    std::string out = "frames";
    uint32_t width = 640;
    uint32_t height = 360;
    uint32_t spp = 8;
    float exposure = 0.0f;
    bool exr = false;
};

bool parse_u32(const char* s, uint32_t& out) {
    char* end = nullptr;
    const unsigned long v = std::strtoul(s, &end, 10);
    if (!s[0] || *end || v == 0 || v > 16384) return false;
    out = static_cast<uint32_t>(v);
    return true;
}

constexpr const char* USAGE =
    "usage: strata-demo [--out DIR] [--width W] [--height H] [--spp N] [--exposure EV] [--exr]\n"
    "       strata-demo --version\n";

int usage(const char* why) {
    std::fprintf(stderr, "strata-demo: %s\n%s", why, USAGE);
    return 2;
}

void print_report(const char* what, const strata::RebuildReport& r) {
    std::printf("%-34s %s\n", what, r.summary().c_str());
    for (const auto& e : r.rebuilt)
        std::printf("%36s rebuilt %-8s %-18s %s\n", "", e.mesh.c_str(),
                    strata::build_reason_name(e.reason), e.detail.c_str());
    for (const auto& e : r.refit)
        std::printf("%36s refit   %-8s %-18s %s\n", "", e.mesh.c_str(),
                    strata::build_reason_name(e.reason), e.detail.c_str());
}

}  // namespace

int main(int argc, char** argv) {
    Options opt;
    for (int i = 1; i < argc; ++i) {
        const bool has_value = i + 1 < argc;
        if (!std::strcmp(argv[i], "--out") && has_value) {
            opt.out = argv[++i];
        } else if (!std::strcmp(argv[i], "--width") && has_value) {
            if (!parse_u32(argv[++i], opt.width)) return usage("bad --width");
        } else if (!std::strcmp(argv[i], "--height") && has_value) {
            if (!parse_u32(argv[++i], opt.height)) return usage("bad --height");
        } else if (!std::strcmp(argv[i], "--spp") && has_value) {
            if (!parse_u32(argv[++i], opt.spp)) return usage("bad --spp");
        } else if (!std::strcmp(argv[i], "--exposure") && has_value) {
            char* end = nullptr;
            opt.exposure = std::strtof(argv[++i], &end);
            if (*end) return usage("bad --exposure");
        } else if (!std::strcmp(argv[i], "--exr")) {
            opt.exr = true;
        } else if (!std::strcmp(argv[i], "--version")) {
            std::printf("strata-demo %s\n", strata::VERSION);
            return 0;
        } else if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
            std::fputs(USAGE, stdout);
            return 0;
        } else {
            return usage((std::string("unknown argument ") + argv[i]).c_str());
        }
    }
    std::error_code ec;
    std::filesystem::create_directories(opt.out, ec);
    if (ec) return usage(("cannot create " + opt.out + ": " + ec.message()).c_str());

    auto engine = strata::Engine::create();
    if (!engine) {
        std::fprintf(stderr, "strata-demo: %s\n", engine.error().describe().c_str());
        return 1;
    }
    strata::RenderRequest request;
    request.width = opt.width;
    request.height = opt.height;
    request.spp = opt.spp;
    request.exposure = opt.exposure;
    if (opt.exr) {
        request.format = strata::ImageFormat::Exr;
        request.aovs = {strata::Aov::Albedo,   strata::Aov::Normal,     strata::Aov::Depth,
                        strata::Aov::Position, strata::Aov::InstanceId, strata::Aov::PrimitiveId,
                        strata::Aov::MeshId};
    }

    auto render = [&](uint32_t frame, const char* what) -> bool {
        auto image = engine.value()->render(request);
        if (!image) {
            std::fprintf(stderr, "strata-demo: render failed: %s\n",
                         image.error().describe().c_str());
            return false;
        }
        print_report(what, image->info.report);
        std::printf("%36s %u spp, %.1f ms render, %.1f ms encode, %zu bytes\n", "",
                    image->info.samples, image->info.render_ms, image->encode_ms,
                    image->bytes.size());
        char name[64];
        std::snprintf(name, sizeof name, "frame-%02u.%s", frame, opt.exr ? "exr" : "png");
        const std::filesystem::path path = std::filesystem::path(opt.out) / name;
        std::ofstream f(path, std::ios::binary);
        f.write(reinterpret_cast<const char*>(image.value().bytes.data()),
                std::streamsize(image.value().bytes.size()));
        return bool(f);
    };

    static const char* STEP_NAMES[strata::DEMO_STEPS] = {
        "camera moved",        "one instance moved", "ring of 12 moved",    "flag deformed",
        "flag deformed again", "material + light",   "ball re-tessellated", "hide + add mesh"};
    if (auto v = engine.value()->apply(strata::make_demo_scene()); !v) {
        std::fprintf(stderr, "strata-demo: %s\n", v.error().describe().c_str());
        return 1;
    }
    if (!render(0, "initial scene")) return 1;
    for (uint32_t step = 0; step < strata::DEMO_STEPS; ++step) {
        if (auto v = engine.value()->apply(strata::make_demo_step(step)); !v) {
            std::fprintf(stderr, "strata-demo: %s\n", v.error().describe().c_str());
            return 1;
        }
        if (!render(step + 1, STEP_NAMES[step])) return 1;
    }
    if (!render(strata::DEMO_STEPS + 1, "nothing changed")) return 1;
    std::printf("wrote %u frames to %s\n", strata::DEMO_STEPS + 2, opt.out.c_str());
    return 0;
}

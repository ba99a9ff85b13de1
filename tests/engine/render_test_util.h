#pragma once
// Helpers shared by the renderer tests: requests, renders that must succeed, projection of world
// points to pixels, and image comparisons.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "engine/image/exr.h"
#include "tests/engine/test_util.h"

namespace strata::test {

inline RenderRequest request(uint32_t w, uint32_t h, uint32_t spp = 1, std::vector<Aov> aovs = {},
                             ImageFormat format = ImageFormat::Exr) {
    RenderRequest r;
    r.width = w;
    r.height = h;
    r.spp = spp;
    r.aovs = std::move(aovs);
    r.format = format;
    return r;
}

inline Frame render_frame_ok(Engine& engine, const RenderRequest& r) {
    auto f = engine.render_frame(r);
    EXPECT_TRUE(f.has_value()) << (f.has_value() ? "" : f.error().describe());
    return f.has_value() ? std::move(f.value()) : Frame{};
}

inline EncodedFrame render_ok(Engine& engine, const RenderRequest& r) {
    auto f = engine.render(r);
    EXPECT_TRUE(f.has_value()) << (f.has_value() ? "" : f.error().describe());
    return f.has_value() ? std::move(f.value()) : EncodedFrame{};
}

inline DecodedExr decode_exr_ok(const std::string& bytes) {
    auto d = decode_exr(bytes);
    EXPECT_TRUE(d.has_value()) << (d.has_value() ? "" : d.error().describe());
    return d.has_value() ? std::move(d.value()) : DecodedExr{};
}

/// The continuous image position (pixels, (0, 0) the top-left corner) where world point `p`
/// projects through `cam` in a w x h frame: the inverse of CameraRays.
inline glm::vec2 project(const Camera& cam, uint32_t w, uint32_t h, const Vec3& p) {
    const Vec3 forward = glm::normalize(cam.target - cam.eye);
    const Vec3 right = glm::normalize(glm::cross(forward, cam.up));
    const Vec3 up = glm::cross(right, forward);
    const Vec3 d = p - cam.eye;
    const float z = glm::dot(d, forward);
    const float tan_half = std::tan(glm::radians(cam.fov_y_deg) * 0.5f);
    const float aspect = float(w) / float(h);
    const float sx = glm::dot(d, right) / z / (tan_half * aspect);
    const float sy = glm::dot(d, up) / z / tan_half;
    return {0.5f * float(w) * (1.0f + sx), 0.5f * float(h) * (1.0f - sy)};
}

inline std::size_t pixel_index(uint32_t w, glm::vec2 pos) {
    return std::size_t(uint32_t(pos.y)) * w + uint32_t(pos.x);
}

/// Root-mean-square difference of two linear images.
inline double rms_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    EXPECT_EQ(a.size(), b.size());
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
        const Vec3 d = a[i] - b[i];
        sum += double(glm::dot(d, d));
    }
    return a.empty() ? 0.0 : std::sqrt(sum / double(a.size()));
}

/// An engine holding `batch`, with the camera of `cam`.
inline std::unique_ptr<Engine> engine_with(EditBatch batch) {
    auto engine = make_engine();
    auto r = engine->apply(std::move(batch));
    EXPECT_TRUE(r.has_value()) << (r.has_value() ? "" : r.error().describe());
    return engine;
}

inline SetCamera camera_edit(const Camera& c) {
    SetCamera s;
    s.eye = c.eye;
    s.target = c.target;
    s.up = c.up;
    s.fov_y_deg = c.fov_y_deg;
    return s;
}

}  // namespace strata::test

#include "engine/render/aov_filter.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {

namespace {

/// Smallest albedo a colour is divided by (dark materials keep their own noise).
constexpr float MIN_ALBEDO = 0.02f;
constexpr float B3[5] = {1.0f / 16, 1.0f / 4, 3.0f / 8, 1.0f / 4, 1.0f / 16};

float luminance(const Vec3& c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

float max_abs(const Vec3& v) {
    return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}

template <class F>
void for_rows(uint32_t height, F&& f) {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, height, 8),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t y = r.begin(); y < r.end(); ++y) f(y);
                      });
}

}  // namespace

void filter_frame(FrameBuffers& b, const AovFilterSettings& settings) {
    const uint32_t w = b.width, h = b.height;
    const std::size_t n = std::size_t(w) * h;
    if (n == 0 || b.albedo.size() != n || b.normal.size() != n || b.depth.size() != n) return;

    // Step: demodulate, unit normals, and the local noise level of each covered pixel.
    std::vector<Vec3> albedo(n), normal(n), light(n), next(n);
    std::vector<float> lum(n), sigma(n);
    std::vector<uint8_t> covered(n);
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            covered[p] = std::isfinite(b.depth[p]) ? 1 : 0;
            albedo[p] = glm::max(b.albedo[p], Vec3(MIN_ALBEDO));
            const float len = glm::length(b.normal[p]);
            normal[p] = len > 0.0f ? b.normal[p] / len : Vec3(0.0f);
            light[p] = covered[p] ? b.color[p] / albedo[p] : b.color[p];
            lum[p] = luminance(light[p]);
        }
    });
    // Fireflies (a pixel far brighter than every neighbour: a rare bright path) would be spread
    // over the whole kernel; they are clamped to their brightest neighbour first.
    std::vector<Vec3> clamped(light);
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!covered[p]) continue;
            float brightest = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int qx = int(x) + dx, qy = int(y) + dy;
                    if ((dx == 0 && dy == 0) || qx < 0 || qy < 0 || qx >= int(w) || qy >= int(h))
                        continue;
                    const std::size_t q = std::size_t(qy) * w + std::size_t(qx);
                    if (covered[q]) brightest = std::max(brightest, lum[q]);
                }
            }
            if (lum[p] > brightest && lum[p] > 0.0f) clamped[p] = light[p] * (brightest / lum[p]);
        }
    });
    light.swap(clamped);
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            lum[p] = luminance(light[p]);
        }
    });
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!covered[p]) continue;
            float sum = 0.0f, sum2 = 0.0f, count = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int qx = int(x) + dx, qy = int(y) + dy;
                    if (qx < 0 || qy < 0 || qx >= int(w) || qy >= int(h)) continue;
                    const std::size_t q = std::size_t(qy) * w + std::size_t(qx);
                    if (!covered[q]) continue;
                    sum += lum[q];
                    sum2 += lum[q] * lum[q];
                    count += 1.0f;
                }
            }
            const float mean = sum / count;
            sigma[p] = std::sqrt(std::max(0.0f, sum2 / count - mean * mean));
        }
    });

    // Step: à-trous passes over the demodulated lighting.
    for (uint32_t it = 0; it < settings.iterations; ++it) {
        const int step = 1 << it;
        for_rows(h, [&](uint32_t y) {
            for (uint32_t x = 0; x < w; ++x) {
                const std::size_t p = std::size_t(y) * w + x;
                if (!covered[p]) {
                    next[p] = light[p];
                    continue;
                }
                const float zp = b.depth[p];
                const float lp = lum[p];
                const float l_scale = 1.0f / (settings.luminance_sigma * sigma[p] + 1e-3f);
                Vec3 sum(0.0f);
                float weights = 0.0f;
                for (int j = -2; j <= 2; ++j) {
                    const int qy = int(y) + j * step;
                    if (qy < 0 || qy >= int(h)) continue;
                    for (int i = -2; i <= 2; ++i) {
                        const int qx = int(x) + i * step;
                        if (qx < 0 || qx >= int(w)) continue;
                        const std::size_t q = std::size_t(qy) * w + std::size_t(qx);
                        if (!covered[q]) continue;
                        const float distance = float(step) * std::sqrt(float(i * i + j * j));
                        const float cos_n = std::max(0.0f, glm::dot(normal[p], normal[q]));
                        const float wz = std::abs(zp - b.depth[q]) /
                                         (settings.depth_sigma * zp * std::max(distance, 1.0f));
                        const float wa = max_abs(albedo[p] - albedo[q]) / settings.albedo_sigma;
                        const float wl = std::abs(lp - lum[q]) * l_scale;
                        const float weight = B3[i + 2] * B3[j + 2] *
                                             std::pow(cos_n, settings.normal_power) *
                                             std::exp(-(wz + wa + wl));
                        sum += weight * light[q];
                        weights += weight;
                    }
                }
                next[p] = weights > 0.0f ? sum / weights : light[p];
            }
        });
        light.swap(next);
        for_rows(h, [&](uint32_t y) {
            for (uint32_t x = 0; x < w; ++x) {
                const std::size_t p = std::size_t(y) * w + x;
                lum[p] = luminance(light[p]);
            }
        });
    }

    // Step: remodulate.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (covered[p]) b.color[p] = light[p] * albedo[p];
        }
    });
}

}  // namespace strata

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
/// Taps whose edge-stopping exponent is past this weigh under 1e-9 of an alike tap: skipped.
constexpr float MAX_EXPONENT = 20.0f;
/// Added to a noise deviation before dividing by it (a noise-free pixel takes only equal taps).
constexpr float MIN_DEVIATION = 1e-6f;

float max_abs(const Vec3& v) {
    return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}

float pow_int(float x, uint32_t n) {
    float r = 1.0f;
    while (n) {
        if (n & 1u) r *= x;
        x *= x;
        n >>= 1;
    }
    return r;
}

template <class F>
void for_rows(uint32_t height, F&& f) {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, height, 8),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t y = r.begin(); y < r.end(); ++y) f(y);
                      });
}

/// The covered pixels' `in`, blurred by a 3x3 binomial kernel over covered pixels only.
void blur3(uint32_t w, uint32_t h, const std::vector<uint8_t>& covered,
           const std::vector<float>& in, std::vector<float>& out) {
    constexpr float K[3] = {0.25f, 0.5f, 0.25f};
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!covered[p]) {
                out[p] = in[p];
                continue;
            }
            float sum = 0.0f, weights = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                const int qy = int(y) + dy;
                if (qy < 0 || qy >= int(h)) continue;
                for (int dx = -1; dx <= 1; ++dx) {
                    const int qx = int(x) + dx;
                    if (qx < 0 || qx >= int(w)) continue;
                    const std::size_t q = std::size_t(qy) * w + std::size_t(qx);
                    if (!covered[q]) continue;
                    const float k = K[dx + 1] * K[dy + 1];
                    sum += k * in[q];
                    weights += k;
                }
            }
            out[p] = sum / weights;
        }
    });
}

}  // namespace

void filter_frame(FrameBuffers& b, std::span<const float> pixel_variance,
                  const AovFilterSettings& settings) {
    const uint32_t w = b.width, h = b.height;
    const std::size_t n = std::size_t(w) * h;
    if (n == 0 || b.albedo.size() != n || b.normal.size() != n || b.depth.size() != n) return;
    const bool measured = pixel_variance.size() == n;

    // Step: demodulate, unit normals.
    std::vector<Vec3> albedo(n), normal(n), light(n), next(n);
    std::vector<float> lum(n), variance(n), smooth(n), next_variance(n);
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

    // Step: each pixel's noise variance in demodulated units: measured (the colour's luminance
    // variance, scaled as demodulation scales the luminance), else the spatial 3x3 variance.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!covered[p]) {
                variance[p] = 0.0f;
                continue;
            }
            if (measured) {
                const float lc = luminance(b.color[p]);
                const float scale =
                    lc > 1e-6f ? lum[p] / lc : 1.0f / std::max(luminance(albedo[p]), MIN_ALBEDO);
                variance[p] = std::max(0.0f, pixel_variance[p]) * scale * scale;
                continue;
            }
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
            variance[p] = std::max(0.0f, sum2 / count - mean * mean);
        }
    });
    // A variance from a few samples is itself noisy: it is smoothed (SVGF does the same).
    blur3(w, h, covered, variance, smooth);
    variance.swap(smooth);
    std::vector<float> deviation(n);  // of the unfiltered pixel, for the last step
    for (std::size_t p = 0; p < n; ++p) deviation[p] = std::sqrt(variance[p]);
    const std::vector<Vec3> original = light;

    // Step: fireflies (a rare bright path in one pixel) would be spread over the whole kernel;
    // they are brought down toward their brightest neighbour, as far as their noise allows.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            next[p] = light[p];
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
            if (lum[p] > brightest && lum[p] > 0.0f) {
                const float target =
                    std::max(brightest, lum[p] - settings.firefly_sigmas * deviation[p]);
                next[p] = light[p] * (target / lum[p]);
            }
        }
    });
    light.swap(next);
    for (std::size_t p = 0; p < n; ++p) lum[p] = luminance(light[p]);

    // Step: à-trous passes over the demodulated lighting, carrying its variance along.
    for (uint32_t it = 0; it < settings.iterations; ++it) {
        const int step = 1 << it;
        if (it > 0) blur3(w, h, covered, variance, smooth);
        const std::vector<float>& stop = it > 0 ? smooth : variance;
        for_rows(h, [&](uint32_t y) {
            for (uint32_t x = 0; x < w; ++x) {
                const std::size_t p = std::size_t(y) * w + x;
                if (!covered[p]) {
                    next[p] = light[p];
                    next_variance[p] = variance[p];
                    continue;
                }
                const float zp = b.depth[p];
                const float lp = lum[p];
                const float l_scale =
                    1.0f / (settings.luminance_sigma * std::sqrt(stop[p]) + MIN_DEVIATION);
                const float z_scale = 1.0f / (settings.depth_sigma * zp);
                const float a_scale = 1.0f / settings.albedo_sigma;
                Vec3 sum(0.0f);
                float weights = 0.0f, var_sum = 0.0f;
                for (int j = -2; j <= 2; ++j) {
                    const int qy = int(y) + j * step;
                    if (qy < 0 || qy >= int(h)) continue;
                    for (int i = -2; i <= 2; ++i) {
                        const int qx = int(x) + i * step;
                        if (qx < 0 || qx >= int(w)) continue;
                        const std::size_t q = std::size_t(qy) * w + std::size_t(qx);
                        if (!covered[q]) continue;
                        const float cos_n = glm::dot(normal[p], normal[q]);
                        if (!(cos_n > 0.0f)) continue;
                        const float distance = float(step) * std::sqrt(float(i * i + j * j));
                        const float wz =
                            std::abs(zp - b.depth[q]) * z_scale / std::max(distance, 1.0f);
                        const float wa = max_abs(albedo[p] - albedo[q]) * a_scale;
                        const float wl = std::abs(lp - lum[q]) * l_scale;
                        const float e = wz + wa + wl;
                        if (e > MAX_EXPONENT) continue;
                        const float weight = B3[i + 2] * B3[j + 2] *
                                             pow_int(cos_n, settings.normal_power) * std::exp(-e);
                        sum += weight * light[q];
                        weights += weight;
                        var_sum += weight * weight * variance[q];
                    }
                }
                if (weights > 0.0f) {
                    next[p] = sum / weights;
                    next_variance[p] = var_sum / (weights * weights);
                } else {
                    next[p] = light[p];
                    next_variance[p] = variance[p];
                }
            }
        });
        light.swap(next);
        variance.swap(next_variance);
        for (std::size_t p = 0; p < n; ++p) lum[p] = luminance(light[p]);
    }

    // Step: keep each pixel's change while it is within the noise, fade it out beyond (a change
    // far past the noise is more likely lost detail than removed noise), and remodulate.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!covered[p]) continue;
            Vec3 change = light[p] - original[p];
            const float moved = std::abs(luminance(change));
            const float allowed =
                (measured ? settings.change_sigmas : settings.spatial_change_sigmas) * deviation[p];
            if (!(allowed > 0.0f)) continue;  // a noise-free pixel stays as it is
            const float r = moved / allowed;
            change *= 1.0f / (1.0f + r * r);
            b.color[p] += change * albedo[p];
        }
    });
}

}  // namespace strata

#include "engine/render/aov_filter.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

// Speed: the filter works on planes of floats (one per channel) with a border of empty pixels
// wide enough for the widest pass, so no tap needs a bounds check, and the à-trous passes
// filter 4 pixels of a row at once (GCC's vector extensions, one SSE register: 8-float vectors
// with an AVX2 clone were about 25% faster on an AVX2 machine, but clang refuses 32-byte vectors
// in the baseline clone's calls); exp is a short polynomial. At 640x360 a frame
// takes about 17 million tap weights.

namespace strata {

namespace {

/// Smallest albedo a colour is divided by (dark materials keep their own noise).
constexpr float MIN_ALBEDO = 0.02f;
constexpr float B3[5] = {1.0f / 16, 1.0f / 4, 3.0f / 8, 1.0f / 4, 1.0f / 16};
/// Taps whose edge-stopping exponent is past this weigh under 1e-9 of an alike tap: dropped.
constexpr float MAX_EXPONENT = 20.0f;
/// Added to a noise deviation before dividing by it (a noise-free pixel takes only equal taps).
constexpr float MIN_DEVIATION = 1e-6f;

/// Most passes (the border grows with the widest: 64 pixels at 6).
constexpr uint32_t MAX_ITERATIONS = 6;

constexpr uint32_t LANES = 4;
using VecF = float __attribute__((vector_size(4 * LANES)));
using VecI = int32_t __attribute__((vector_size(4 * LANES)));

[[gnu::always_inline]] inline VecF load(const float* p) {
    VecF v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
[[gnu::always_inline]] inline void store(float* p, VecF v) {
    std::memcpy(p, &v, sizeof v);
}
[[gnu::always_inline]] inline VecF splat(float x) {
    return VecF{} + x;
}
[[gnu::always_inline]] inline VecF vabs(VecF v) {
    return VecF(VecI(v) & (VecI{} + 0x7fffffff));
}
/// Lanes of `a` where `mask` is set, of `b` elsewhere (bitwise: NaNs in the other never leak).
[[gnu::always_inline]] inline VecF select(VecI mask, VecF a, VecF b) {
    return VecF((VecI(a) & mask) | (VecI(b) & ~mask));
}
[[gnu::always_inline]] inline VecF vmax(VecF a, VecF b) {
    return select(a > b, a, b);
}

/// exp(-e) for 0 <= e <= MAX_EXPONENT (relative error under 2e-4): 2^t as 2^floor(t), put into
/// the exponent bits, times a degree-5 polynomial for the fraction.
[[gnu::always_inline]] inline VecF exp_negative(VecF e) {
    const VecF t = e * -1.44269504f;
    VecI i = __builtin_convertvector(t, VecI);            // truncation: t <= 0, so i >= t
    i += __builtin_convertvector(i, VecF) > t;            // floor (a true comparison is -1)
    const VecF f = t - __builtin_convertvector(i, VecF);  // [0, 1)
    const VecF p =
        1.0f +
        f * (0.693147181f +
             f * (0.240226507f + f * (0.0555041087f + f * (0.00961812911f + f * 0.00133335581f))));
    return VecF(VecI(p) + (i << 23));
}

/// Planes of w x h pixels inside a border of `pad` empty pixels on every side, rows of
/// `stride` floats (a multiple of LANES past the border, so whole vectors cover every row).
struct Layout {
    uint32_t w = 0, h = 0, pad = 0, stride = 0;
    Layout(uint32_t width, uint32_t height, uint32_t border)
        : w(width),
          h(height),
          pad(border),
          stride(border + (width + LANES - 1) / LANES * LANES + border) {}
    std::size_t size() const { return std::size_t(h + 2 * pad) * stride; }
    std::size_t at(uint32_t x, uint32_t y) const {
        return std::size_t(y + pad) * stride + (x + pad);
    }
    friend bool operator==(const Layout&, const Layout&) = default;
};

using Plane = std::vector<float>;

/// An RGB image as three planes, with the luminance of each pixel.
struct Planes {
    Plane r, g, b, lum;
    explicit Planes(std::size_t n) : r(n), g(n), b(n), lum(n) {}
    void update_luminance(std::size_t p) {
        lum[p] = luminance(Vec3(r[p], g[p], b[p]));
    }
};

/// What the taps are weighed by. Pixels whose camera ray missed, and the border, have covered
/// 0 and zero normal, albedo and depth: a zero normal gives them zero weight as taps, and their
/// own value passes through.
struct Guides {
    Plane covered, nx, ny, nz, ar, ag, ab, z;
    explicit Guides(std::size_t n) {
        for (Plane* p : {&covered, &nx, &ny, &nz, &ar, &ag, &ab, &z}) p->resize(n);
    }
};

}  // namespace

/// Everything filter_frame works in, for one layout.
struct FilterScratch::Buffers {
    Layout layout;
    Guides g;
    Planes light, next, original;
    Plane variance, smooth, next_variance, deviation;
    explicit Buffers(const Layout& l)
        : layout(l),
          g(l.size()),
          light(l.size()),
          next(l.size()),
          original(l.size()),
          variance(l.size()),
          smooth(l.size()),
          next_variance(l.size()),
          deviation(l.size()) {}
    /// Planes per pixel of the layout.
    static constexpr std::size_t PLANES = 8 + 3 * 4 + 4;
};

FilterScratch::FilterScratch() = default;
FilterScratch::~FilterScratch() = default;

std::size_t FilterScratch::bytes() const {
    return buffers ? buffers->layout.size() * Buffers::PLANES * sizeof(float) : 0;
}

void FilterScratch::release() {
    buffers.reset();
}

namespace {

template <class F>
void for_rows(uint32_t height, F&& f) {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, height, 4),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                          for (uint32_t y = r.begin(); y < r.end(); ++y) f(y);
                      });
}

/// The covered pixels' `in`, blurred by a 3x3 binomial kernel over covered pixels only.
void blur3(const Layout& l, const Guides& g, const Plane& in, Plane& out) {
    constexpr float K[3] = {0.25f, 0.5f, 0.25f};
    for_rows(l.h, [&](uint32_t y) {
        for (uint32_t x = 0; x < l.w; ++x) {
            const std::size_t p = l.at(x, y);
            if (g.covered[p] == 0.0f) {
                out[p] = in[p];
                continue;
            }
            float sum = 0.0f, weights = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::size_t q = p + std::size_t(std::ptrdiff_t(dy) * l.stride + dx);
                    const float k = K[dx + 1] * K[dy + 1] * g.covered[q];
                    sum += k * in[q];
                    weights += k;
                }
            }
            out[p] = sum / weights;
        }
    });
}

/// One à-trous pass at `step` over row y, LANES pixels at a time: `in` and `variance`
/// filtered into `out` and `out_variance`, luminance differences measured in deviations of
/// `stop`.
void atrous_row(const Layout& l, const Guides& g,
                                                          const Planes& in, const Plane& variance,
                                                          const Plane& stop, uint32_t step,
                                                          const AovFilterSettings& settings,
                                                          uint32_t y, Planes& out,
                                                          Plane& out_variance) {
    const float normal_power = float(settings.normal_power);
    const VecF a_scale = splat(1.0f / settings.albedo_sigma);
    float kernel[25], inv_distance[25];
    std::ptrdiff_t offset[25];
    for (int j = -2, t = 0; j <= 2; ++j) {
        for (int i = -2; i <= 2; ++i, ++t) {
            kernel[t] = B3[i + 2] * B3[j + 2];
            inv_distance[t] = 1.0f / std::max(1.0f, float(step) * std::sqrt(float(i * i + j * j)));
            offset[t] = (std::ptrdiff_t(j) * l.stride + i) * std::ptrdiff_t(step);
        }
    }
    for (uint32_t x = 0; x < l.w; x += LANES) {
        const std::size_t p = l.at(x, y);
        const VecF pnx = load(&g.nx[p]), pny = load(&g.ny[p]), pnz = load(&g.nz[p]);
        const VecF pz = load(&g.z[p]), pl = load(&in.lum[p]);
        const VecF par = load(&g.ar[p]), pag = load(&g.ag[p]), pab = load(&g.ab[p]);
        const VecI covered = load(&g.covered[p]) > 0.0f;
        VecF l_scale, z_scale;
        for (uint32_t k = 0; k < LANES; ++k) {
            l_scale[k] = 1.0f / (settings.luminance_sigma * std::sqrt(stop[p + k]) + MIN_DEVIATION);
            z_scale[k] =
                g.covered[p + k] > 0.0f ? 1.0f / (settings.depth_sigma * g.z[p + k]) : 0.0f;
        }
        VecF sr{}, sg{}, sb{}, sw{}, sv{};
        for (int t = 0; t < 25; ++t) {
            const std::size_t q = p + std::size_t(offset[t]);
            // The normal weight cos^normal_power as exp(normal_power * ln cos), ln cos by its
            // series in d = 1 - cos (close for the cosines near 1 that weigh anything at the
            // default power: at cos 0.72 the weight is already e^-20). Back faces never weigh.
            const VecF c = pnx * load(&g.nx[q]) + pny * load(&g.ny[q]) + pnz * load(&g.nz[q]);
            const VecF d = 1.0f - c;
            const VecF wn = normal_power * d * (1.0f + d * (0.5f + d * (1.0f / 3.0f)));
            const VecF wz = vabs(pz - load(&g.z[q])) * z_scale * inv_distance[t];
            const VecF wa = vmax(vabs(par - load(&g.ar[q])),
                                 vmax(vabs(pag - load(&g.ag[q])), vabs(pab - load(&g.ab[q])))) *
                            a_scale;
            const VecF wl = vabs(pl - load(&in.lum[q])) * l_scale;
            const VecF exponent = wn + wz + wa + wl;
            const VecI alike = (exponent < MAX_EXPONENT) & (c > 0.0f);  // false for NaN too
            const VecF weight =
                select(alike, kernel[t] * exp_negative(select(alike, exponent, VecF{})), VecF{});
            sr += weight * load(&in.r[q]);
            sg += weight * load(&in.g[q]);
            sb += weight * load(&in.b[q]);
            sw += weight;
            sv += weight * weight * load(&variance[q]);
        }
        // Pixels with no weight (a zero normal) and uncovered ones keep their value.
        const VecI keep = ~(covered & (sw > 0.0f));
        const VecF inv = 1.0f / select(keep, splat(1.0f), sw);
        const VecF r = select(keep, load(&in.r[p]), sr * inv);
        const VecF gg = select(keep, load(&in.g[p]), sg * inv);
        const VecF b = select(keep, load(&in.b[p]), sb * inv);
        store(&out.r[p], r);
        store(&out.g[p], gg);
        store(&out.b[p], b);
        store(&out.lum[p], 0.2126f * r + 0.7152f * gg + 0.0722f * b);  // luminance(), 4 lanes
        store(&out_variance[p], select(keep, load(&variance[p]), sv * inv * inv));
    }
}

}  // namespace

void filter_frame(FrameBuffers& b, std::span<const float> pixel_variance, uint32_t samples,
                  const AovFilterSettings& settings, FilterScratch* scratch) {
    const uint32_t w = b.width, h = b.height;
    const std::size_t n = std::size_t(w) * h;
    if (n == 0 || b.albedo.size() != n || b.normal.size() != n || b.depth.size() != n) return;
    const bool measured = pixel_variance.size() == n;
    const uint32_t iterations = std::min(settings.iterations, MAX_ITERATIONS);
    // The widest pass reaches 2 steps of 2^(iterations - 1) pixels; the 3x3 steps reach 1.
    const Layout l(w, h, std::max(1u, iterations > 0 ? 2u << (iterations - 1) : 1u));
    const std::size_t size = l.size();
    // Every step writes every pixel inside the border, and nothing writes the border, so reused
    // buffers of the same layout need no clearing.
    FilterScratch own;
    if (!scratch) scratch = &own;
    if (!scratch->buffers || !(scratch->buffers->layout == l)) {
        scratch->buffers.reset();  // the old layout's memory goes first
        scratch->buffers = std::make_unique<FilterScratch::Buffers>(l);
    }
    FilterScratch::Buffers& s = *scratch->buffers;
    Guides& g = s.g;
    Planes &light = s.light, &next = s.next, &original = s.original;
    Plane &variance = s.variance, &smooth = s.smooth, &next_variance = s.next_variance;
    Plane& deviation = s.deviation;
    // The firefly step's noise level, in a plane the passes use later.
    Plane& firefly_deviation = s.next_variance;
    const float inv_samples = 1.0f / float(std::max(1u, samples));

    // Step: the guides as planes (unit normals), and the demodulated lighting.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * w + x, p = l.at(x, y);
            const bool hit = std::isfinite(b.depth[i]);
            const Vec3 albedo = glm::max(b.albedo[i], Vec3(MIN_ALBEDO));
            const float len = glm::length(b.normal[i]);
            const Vec3 normal = hit && len > 0.0f ? b.normal[i] / len : Vec3(0.0f);
            const Vec3 c = hit ? b.color[i] / albedo : b.color[i];
            g.covered[p] = hit ? 1.0f : 0.0f;
            g.z[p] = hit ? b.depth[i] : 0.0f;
            g.nx[p] = normal.x, g.ny[p] = normal.y, g.nz[p] = normal.z;
            g.ar[p] = hit ? albedo.x : 0.0f, g.ag[p] = hit ? albedo.y : 0.0f;
            g.ab[p] = hit ? albedo.z : 0.0f;
            light.r[p] = c.x, light.g[p] = c.y, light.b[p] = c.z;
            light.update_luminance(p);
        }
    });

    // Step: each pixel's noise variance in demodulated units: measured (the colour's luminance
    // variance, scaled as demodulation scales the luminance), else the spatial 3x3 variance.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * w + x, p = l.at(x, y);
            if (g.covered[p] == 0.0f) {
                variance[p] = 0.0f;
                continue;
            }
            if (measured) {
                const float lc = luminance(b.color[i]);
                const float la = luminance(Vec3(g.ar[p], g.ag[p], g.ab[p]));
                const float scale =
                    lc > 1e-6f ? light.lum[p] / lc : 1.0f / std::max(la, MIN_ALBEDO);
                const float independent = std::max(0.0f, pixel_variance[i]) * scale * scale;
                variance[p] = independent * inv_samples;
                firefly_deviation[p] = std::sqrt(independent);
                continue;
            }
            float sum = 0.0f, sum2 = 0.0f, count = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::size_t q = p + std::size_t(std::ptrdiff_t(dy) * l.stride + dx);
                    const float c = g.covered[q];
                    sum += c * light.lum[q];
                    sum2 += c * light.lum[q] * light.lum[q];
                    count += c;
                }
            }
            const float mean = sum / count;
            variance[p] = std::max(0.0f, sum2 / count - mean * mean);
            firefly_deviation[p] = std::sqrt(variance[p]);
        }
    });
    // A variance from a few samples is itself noisy: it is smoothed (SVGF does the same).
    blur3(l, g, variance, smooth);
    variance.swap(smooth);
    // The unfiltered pixel's noise deviation, for the last step.
    for (std::size_t p = 0; p < size; ++p) deviation[p] = std::sqrt(variance[p]);

    // Step: fireflies (a rare bright path in one pixel) would be spread over the whole kernel;
    // they are brought down toward their brightest neighbour, as far as their noise allows.
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t p = l.at(x, y);
            next.r[p] = light.r[p], next.g[p] = light.g[p], next.b[p] = light.b[p];
            next.lum[p] = light.lum[p];
            if (g.covered[p] == 0.0f) continue;
            float brightest = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const std::size_t q = p + std::size_t(std::ptrdiff_t(dy) * l.stride + dx);
                    if (q != p && g.covered[q] > 0.0f)
                        brightest = std::max(brightest, light.lum[q]);
                }
            }
            const float lp = light.lum[p];
            if (!(lp > brightest && lp > 0.0f)) continue;
            // Measured noise: a pixel whose excess over its brightest neighbour is within the
            // noise is taken down to that neighbour; a larger excess is signal (a highlight)
            // and stays. Spatial noise (which counts the firefly itself): taken down by at
            // most firefly_sigmas deviations.
            const float target =
                measured ? (lp - brightest <= settings.firefly_noise_sigmas * firefly_deviation[p]
                                ? brightest
                                : lp)
                         : std::max(brightest, lp - settings.firefly_sigmas * firefly_deviation[p]);
            const float scale = target / lp;
            next.r[p] *= scale, next.g[p] *= scale, next.b[p] *= scale;
            next.update_luminance(p);
        }
    });
    // What the last step measures changes from: with a measured noise level, the lighting the
    // passes start from (the firefly step's change is final: the samples' spread told a firefly
    // from a highlight); with the spatial estimate, the lighting before the firefly step (a
    // 1-sample frame cannot tell a firefly from a small highlight, so that change is judged
    // like the passes').
    if (!measured) original = light;
    std::swap(light, next);
    if (measured) original = light;

    // Step: à-trous passes over the demodulated lighting, carrying its variance along.
    for (uint32_t it = 0; it < iterations; ++it) {
        if (it > 0) blur3(l, g, variance, smooth);
        const Plane& stop = it > 0 ? smooth : variance;
        for_rows(h, [&](uint32_t y) {
            atrous_row(l, g, light, variance, stop, 1u << it, settings, y, next, next_variance);
        });
        std::swap(light, next);
        variance.swap(next_variance);
    }

    // Step: keep each pixel's change while it is within the noise, fade it out beyond (a change
    // far past the noise is more likely lost detail than removed noise), and remodulate.
    // A noise level measured from few samples is itself uncertain (from 4 samples, its standard
    // error is about 40%): the fade starts farther out the fewer samples there are.
    const float k =
        measured ? std::min(settings.few_samples_change_sigmas,
                            settings.change_sigmas +
                                0.5f * std::max(0.0f, std::log2(float(settings.converged_samples) /
                                                                float(std::max(1u, samples)))))
                 : settings.spatial_change_sigmas;
    for_rows(h, [&](uint32_t y) {
        for (uint32_t x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * w + x, p = l.at(x, y);
            if (g.covered[p] == 0.0f) continue;
            const float allowed = k * deviation[p];
            if (!(allowed > 0.0f)) continue;  // a noise-free pixel stays as it is
            const float r = std::abs(light.lum[p] - original.lum[p]) / allowed;
            const float keep = 1.0f / (1.0f + r * r);
            // From `original`, not the input: that holds the firefly step's change.
            b.color[i] = Vec3((original.r[p] + keep * (light.r[p] - original.r[p])) * g.ar[p],
                              (original.g[p] + keep * (light.g[p] - original.g[p])) * g.ag[p],
                              (original.b[p] + keep * (light.b[p] - original.b[p])) * g.ab[p]);
        }
    });
}

}  // namespace strata

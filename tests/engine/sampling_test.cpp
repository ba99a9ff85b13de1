// The sample sequence (range, stratification, independence between pixels, blue-noise spread of
// neighbouring pixels' samples), the blue-noise mask, and the BRDF (its importance sampling
// agrees with its evaluation; energy is conserved).

#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "engine/render/blue_noise.h"
#include "engine/render/sampler.h"
#include "engine/render/shading.h"

namespace strata {
namespace {

TEST(PixelSampler, ValuesAreInTheUnitInterval) {
    const PixelSampler s(17, 3);
    for (uint32_t i = 0; i < 4096; ++i) {
        for (uint32_t g = 0; g < 3; ++g) {
            for (float v : s.get4(i, g)) {
                ASSERT_GE(v, 0.0f);
                ASSERT_LT(v, 1.0f);
            }
        }
    }
}

TEST(PixelSampler, FirstPowerOfTwoSamplesAreStratifiedInEveryDimension) {
    for (uint32_t px = 0; px < 4; ++px) {
        const PixelSampler s(px, 7 * px + 1);
        for (uint32_t m = 1; m <= 10; ++m) {
            const uint32_t n = 1u << m;
            for (uint32_t dim = 0; dim < 8; ++dim) {
                std::set<uint32_t> strata;
                for (uint32_t i = 0; i < n; ++i) strata.insert(uint32_t(s.get1(i, dim) * float(n)));
                ASSERT_EQ(strata.size(), n)
                    << "pixel " << px << ", dimension " << dim << ", 2^" << m;
            }
        }
    }
}

TEST(PixelSampler, PixelJitterFormsNets) {
    // The first 2^m samples put exactly one point in every 2^a x 2^(m-a) cell of dimensions
    // (0, 1), the pixel jitter: the (0, m, 2)-net property of Sobol's first two dimensions, which
    // Owen scrambling and the index shuffle preserve.
    for (uint32_t px = 0; px < 3; ++px) {
        const PixelSampler s(5 + px, 9);
        for (uint32_t m = 2; m <= 10; m += 2) {
            const uint32_t n = 1u << m;
            for (uint32_t a = 0; a <= m; ++a) {
                std::set<std::pair<uint32_t, uint32_t>> cells;
                for (uint32_t i = 0; i < n; ++i) {
                    const auto u = s.get4(i, 0);
                    cells.insert(
                        {uint32_t(u[0] * float(1u << a)), uint32_t(u[1] * float(1u << (m - a)))});
                }
                ASSERT_EQ(cells.size(), n) << "2^" << m << " samples, a = " << a;
            }
        }
    }
}

TEST(PixelSampler, GroupAndGet1Agree) {
    const PixelSampler s(3, 4);
    for (uint32_t i = 0; i < 64; ++i) {
        const auto g1 = s.get4(i, 1);
        for (uint32_t d = 0; d < 4; ++d) ASSERT_EQ(s.get1(i, 4 + d), g1[d]);
    }
}

TEST(PixelSampler, NeighbouringPixelsAreDecorrelated) {
    const PixelSampler a(10, 10), b(11, 10), c(10, 11);
    int same = 0;
    for (uint32_t i = 0; i < 256; ++i) {
        same += a.get1(i, 0) == b.get1(i, 0);
        same += a.get1(i, 0) == c.get1(i, 0);
    }
    EXPECT_LT(same, 4);
}

TEST(BlueNoiseMask, HoldsEveryRankOnceAndIsTheSameEachTime) {
    const BlueNoiseMask& mask = blue_noise_mask();
    std::set<uint16_t> ranks(mask.begin(), mask.end());
    EXPECT_EQ(ranks.size(), BLUE_NOISE_PIXELS);
    EXPECT_EQ(*ranks.rbegin(), BLUE_NOISE_PIXELS - 1);
    EXPECT_EQ(make_blue_noise_mask(), mask);
}

/// Squared distance between pixels p and q of the mask's tile, on the torus.
uint32_t torus_distance2(uint32_t p, uint32_t q) {
    const auto axis = [](uint32_t a, uint32_t b) {
        const uint32_t d = a > b ? a - b : b - a;
        return std::min(d, BLUE_NOISE_SIZE - d);
    };
    const uint32_t dx = axis(p % BLUE_NOISE_SIZE, q % BLUE_NOISE_SIZE);
    const uint32_t dy = axis(p / BLUE_NOISE_SIZE, q / BLUE_NOISE_SIZE);
    return dx * dx + dy * dy;
}

TEST(BlueNoiseMask, EveryThresholdIsSpreadEvenly) {
    // White noise fails both: 256 random pixels of 4096 almost surely include two closer than 2,
    // and the count of 64 fair coins strays past 32 +- 8 in some of 64 blocks.
    const BlueNoiseMask& mask = blue_noise_mask();
    for (uint32_t threshold : {64u, 256u}) {
        std::vector<uint32_t> set;
        for (uint32_t p = 0; p < BLUE_NOISE_PIXELS; ++p)
            if (mask[p] < threshold) set.push_back(p);
        uint32_t closest = ~0u;
        for (std::size_t i = 0; i < set.size(); ++i)
            for (std::size_t j = i + 1; j < set.size(); ++j)
                closest = std::min(closest, torus_distance2(set[i], set[j]));
        EXPECT_GE(closest, threshold == 64u ? 16u : 4u) << "ranks below " << threshold;
    }
    for (uint32_t by = 0; by < BLUE_NOISE_SIZE; by += 8) {
        for (uint32_t bx = 0; bx < BLUE_NOISE_SIZE; bx += 8) {
            uint32_t low = 0;
            for (uint32_t y = by; y < by + 8; ++y)
                for (uint32_t x = bx; x < bx + 8; ++x)
                    low += mask[y * BLUE_NOISE_SIZE + x] < BLUE_NOISE_PIXELS / 2;
            EXPECT_NEAR(double(low), 32.0, 4.0) << "block " << bx << ", " << by;
        }
    }
}

TEST(PixelSampler, NeighboursFirstSamplesAreSpreadApart) {
    // Sample 0 of neighbouring pixels: independent uniform values lie 1/3 apart on average;
    // the blue-noise shifts push them farther apart in every dimension the renderer uses.
    for (uint32_t dim = 0; dim < 16; ++dim) {
        double sum = 0.0;
        uint32_t count = 0;
        for (uint32_t y = 0; y < 64; ++y) {
            for (uint32_t x = 0; x < 64; ++x) {
                const float u = PixelSampler(x, y).get1(0, dim);
                sum += std::abs(u - PixelSampler(x + 1, y).get1(0, dim));
                sum += std::abs(u - PixelSampler(x, y + 1).get1(0, dim));
                count += 2;
            }
        }
        EXPECT_GT(sum / count, 0.38) << "dimension " << dim;
    }
}

/// Directional albedo of `bsdf` for view angle theta, two ways: the mean weight of its own
/// importance sampling, and uniform hemisphere sampling of eval_cos.
std::pair<double, double> albedo_two_ways(const Bsdf& bsdf, float theta, int n) {
    const Vec3 normal(0.0f, 0.0f, 1.0f);
    const Vec3 v(std::sin(theta), 0.0f, std::cos(theta));
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    double importance = 0.0, uniform = 0.0;
    for (int i = 0; i < n; ++i) {
        const BsdfSample s = bsdf.sample(normal, v, u(rng), u(rng), u(rng));
        if (s.valid) importance += double(s.weight.y);
        const float z = u(rng), phi = 2.0f * std::numbers::pi_v<float> * u(rng);
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        const Vec3 l(r * std::cos(phi), r * std::sin(phi), z);
        uniform += double(bsdf.eval_cos(normal, v, l).y) * 2.0 * std::numbers::pi;
    }
    return {importance / n, uniform / n};
}

struct BsdfCase {
    float roughness;
    float metallic;
    float theta;
};

class BsdfSampling : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfSampling, ImportanceSamplingAgreesWithEvaluation) {
    const BsdfCase c = GetParam();
    const Bsdf bsdf(Material{Vec3(0.7f), c.roughness, c.metallic, Vec3(0.0f)});
    const auto [importance, uniform] = albedo_two_ways(bsdf, c.theta, 400000);
    EXPECT_NEAR(importance, uniform, 0.02 * uniform + 0.002);
    EXPECT_LE(importance, 1.0);
    EXPECT_GT(importance, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Materials, BsdfSampling,
                         ::testing::Values(BsdfCase{1.0f, 0.0f, 0.2f}, BsdfCase{0.5f, 0.0f, 0.9f},
                                           BsdfCase{0.4f, 1.0f, 0.3f}, BsdfCase{0.6f, 0.5f, 1.2f},
                                           BsdfCase{0.3f, 0.0f, 0.0f}));

TEST(Bsdf, WhiteMaterialsReflectAtMostAllLight) {
    for (float roughness : {0.05f, 0.3f, 1.0f}) {
        for (float metallic : {0.0f, 1.0f}) {
            const Bsdf bsdf(Material{Vec3(1.0f), roughness, metallic, Vec3(0.0f)});
            std::mt19937 rng(7);
            std::uniform_real_distribution<float> u(0.0f, 1.0f);
            double sum = 0.0;
            const Vec3 n(0.0f, 0.0f, 1.0f), v = glm::normalize(Vec3(0.5f, 0.0f, 1.0f));
            for (int i = 0; i < 100000; ++i) {
                const BsdfSample s = bsdf.sample(n, v, u(rng), u(rng), u(rng));
                if (s.valid) sum += double(s.weight.x);
            }
            EXPECT_LE(sum / 100000.0, 1.01) << roughness << " " << metallic;
        }
    }
}

TEST(Bsdf, NothingBelowTheSurface) {
    const Bsdf bsdf(Material{});
    const Vec3 n(0.0f, 0.0f, 1.0f);
    EXPECT_EQ(bsdf.eval_cos(n, Vec3(0, 0, 1), glm::normalize(Vec3(1, 0, -0.1f))), Vec3(0.0f));
    EXPECT_EQ(bsdf.eval_cos(n, glm::normalize(Vec3(1, 0, -0.1f)), Vec3(0, 0, 1)), Vec3(0.0f));
    EXPECT_FALSE(bsdf.sample(n, glm::normalize(Vec3(1, 0, -0.1f)), 0.5f, 0.5f, 0.5f).valid);
}

TEST(SkyModel, ZenithIsTheSkyColorAndBelowTheHorizonIsDimmer) {
    Lighting l;
    l.sky_color = Vec3(0.2f, 0.4f, 0.8f);
    l.sky_intensity = 2.0f;
    const SkyModel sky(l);
    EXPECT_EQ(sky.radiance(Vec3(0, 1, 0)), l.sky_color * 2.0f);
    const Vec3 horizon = sky.radiance(Vec3(1, 0, 0));
    EXPECT_NEAR(horizon.x, 0.5f * 1.2f * 2.0f, 1e-6f);
    EXPECT_LT(sky.radiance(Vec3(0, -1, 0)).z, horizon.z);
    EXPECT_NEAR(glm::length(sky.sun_direction()), 1.0f, 1e-6f);
    EXPECT_NEAR(sky.sun_irradiance().x, std::numbers::pi_v<float> * l.sun_color.x, 1e-5f);
}

}  // namespace
}  // namespace strata

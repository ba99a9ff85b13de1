// The sample sequence (range, stratification, independence between pixels) and the BRDF (its
// importance sampling agrees with its evaluation; energy is conserved).

#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include <gtest/gtest.h>

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

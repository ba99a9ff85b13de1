#pragma once
// Deterministic per-pixel sample sequence: shuffled, Owen-scrambled Sobol points (Burley 2020,
// "Practical Hash-based Owen Scrambling", with Vegdahl's improved Laine-Karras hash), each pixel's
// copy digitally shifted (XOR) by a blue-noise mask (blue_noise.h).
//
// Sample `i` of pixel (x, y) in dimension `d` is a pure function of (x, y, i, d): it does not
// depend on the image size, the tile a pixel falls in, the thread that renders it or on how many
// samples were asked for. That is what makes frames byte-identical for the same inputs, and what
// makes accumulating two launches of k samples equal to one launch of 2k samples.
//
// Dimensions come in groups of four (one 4-D Sobol net each, "padded" with an independent seed
// per group): the first 2^m samples of a pixel are stratified in every group at 2^m strata. The
// shuffle and the scramble are the same for every pixel; what tells pixels apart is the shift of
// each dimension: the top 12 bits of its coordinates are XORed with the pixel's rank in the
// blue-noise mask (read at an offset of its own per dimension). A digital shift keeps the nets
// intact, and sample i of neighbouring pixels then differs the way the mask's ranks do: evenly,
// with no clumps, so a frame's error is fine-grained (blue) rather than blotchy (white).

#include <array>
#include <cstdint>

#include "engine/core/hash.h"
#include "engine/render/blue_noise.h"

namespace strata {

namespace sampler_detail {

/// Sobol direction numbers for the first four dimensions (Joe and Kuo), 32 bits each.
constexpr std::array<std::array<uint32_t, 32>, 4> make_sobol_directions() {
    // Degree s, coefficients a and initial m_k of the primitive polynomials of dimensions 2..4.
    constexpr uint32_t S[3] = {1, 2, 3};
    constexpr uint32_t A[3] = {0, 1, 1};
    constexpr uint32_t M[3][3] = {{1, 0, 0}, {1, 3, 0}, {1, 3, 1}};
    std::array<std::array<uint32_t, 32>, 4> v{};
    for (uint32_t k = 0; k < 32; ++k) v[0][k] = 1u << (31 - k);
    for (uint32_t d = 1; d < 4; ++d) {
        const uint32_t s = S[d - 1], a = A[d - 1];
        for (uint32_t k = 0; k < 32; ++k) {
            if (k < s) {
                v[d][k] = M[d - 1][k] << (31 - k);
                continue;
            }
            uint32_t x = v[d][k - s] ^ (v[d][k - s] >> s);
            for (uint32_t j = 1; j < s; ++j) {
                if ((a >> (s - 1 - j)) & 1u) x ^= v[d][k - j];
            }
            v[d][k] = x;
        }
    }
    return v;
}

inline constexpr std::array<std::array<uint32_t, 32>, 4> SOBOL = make_sobol_directions();

/// Sobol points of 16-bit indices by table: the XOR of the direction numbers of each byte.
constexpr std::array<std::array<std::array<uint32_t, 256>, 2>, 4> make_sobol_bytes() {
    std::array<std::array<std::array<uint32_t, 256>, 2>, 4> t{};
    for (uint32_t d = 0; d < 4; ++d) {
        for (uint32_t half = 0; half < 2; ++half) {
            for (uint32_t b = 0; b < 256; ++b) {
                uint32_t x = 0;
                for (uint32_t bit = 0; bit < 8; ++bit) {
                    if ((b >> bit) & 1u) x ^= SOBOL[d][8 * half + bit];
                }
                t[d][half][b] = x;
            }
        }
    }
    return t;
}

inline constexpr auto SOBOL_BYTES = make_sobol_bytes();

constexpr uint32_t sobol16(uint32_t index, uint32_t dim) {
    return SOBOL_BYTES[dim][0][index & 0xFFu] ^ SOBOL_BYTES[dim][1][(index >> 8) & 0xFFu];
}

constexpr uint32_t reverse_bits(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
    return (x >> 16) | (x << 16);
}

/// Nested uniform (Owen) scramble of the bits of x, read as a binary fraction.
constexpr uint32_t owen_scramble(uint32_t x, uint32_t seed) {
    x = reverse_bits(x);
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return reverse_bits(x);
}

}  // namespace sampler_detail


namespace sampler_detail {

/// The index shuffle's and each dimension's scramble seed of one group of dimensions.
struct GroupSeeds {
    uint32_t index = 0;
    uint32_t dim[4] = {};
};

constexpr GroupSeeds make_group_seeds(uint32_t group) {
    GroupSeeds g;
    g.index = hash_combine(0x5eed5eedu, group);
    for (uint32_t d = 0; d < 4; ++d) g.dim[d] = hash_combine(g.index, d + 1);
    return g;
}

/// Groups whose seeds are a table (the renderer uses four).
constexpr uint32_t TABLED_GROUPS = 8;
inline constexpr std::array<GroupSeeds, TABLED_GROUPS> GROUP_SEEDS = [] {
    std::array<GroupSeeds, TABLED_GROUPS> t{};
    for (uint32_t g = 0; g < TABLED_GROUPS; ++g) t[g] = make_group_seeds(g);
    return t;
}();

}  // namespace sampler_detail

/// The sample sequence of one pixel.
class PixelSampler {
public:
    /// Dimensions one group holds.
    static constexpr uint32_t GROUP = 4;
    /// Sample indices must be below this.
    static constexpr uint32_t MAX_SAMPLES = 1u << 16;

    PixelSampler() = default;
    PixelSampler(uint32_t x, uint32_t y)
        : m_mask(&blue_noise_mask()),
          m_x(x & (BLUE_NOISE_SIZE - 1)),
          m_y(y & (BLUE_NOISE_SIZE - 1)) {}

    /// The 4-D point of sample `index` in dimension group `group`, each coordinate in [0, 1).
    std::array<float, 4> get4(uint32_t index, uint32_t group) const {
        const GroupSeeds g = seeds(group);
        const uint32_t shuffled = shuffle(index, g.index);
        std::array<float, 4> out{};
        for (uint32_t d = 0; d < 4; ++d) out[d] = coordinate(shuffled, d, g, group * GROUP + d);
        return out;
    }

    /// Coordinate `dim` of sample `index` (dimension d is coordinate d % 4 of group d / 4).
    float get1(uint32_t index, uint32_t dim) const {
        const GroupSeeds g = seeds(dim / GROUP);
        return coordinate(shuffle(index, g.index), dim % GROUP, g, dim);
    }

private:
    using GroupSeeds = sampler_detail::GroupSeeds;

    static constexpr GroupSeeds seeds(uint32_t group) {
        using namespace sampler_detail;
        return group < TABLED_GROUPS ? GROUP_SEEDS[group] : make_group_seeds(group);
    }

    /// The digital shift of dimension `dim`: the pixel's blue-noise rank, read at the
    /// dimension's own offset into the mask (an R2 sequence, so that the dimensions' offsets
    /// are far apart), as the top 12 bits.
    uint32_t shift(uint32_t dim) const {
        const uint32_t ox = (0x80000000u + dim * 3242174889u) >> (32 - BLUE_NOISE_LOG2);
        const uint32_t oy = (0x80000000u + dim * 2447445413u) >> (32 - BLUE_NOISE_LOG2);
        constexpr uint32_t wrap = BLUE_NOISE_SIZE - 1;
        const uint32_t rank =
            (*m_mask)[((m_y + oy) & wrap) * BLUE_NOISE_SIZE + ((m_x + ox) & wrap)];
        return rank << (32 - 2 * BLUE_NOISE_LOG2);
    }

    float coordinate(uint32_t shuffled, uint32_t d, const GroupSeeds& g, uint32_t dim) const {
        using namespace sampler_detail;
        return to_unit(owen_scramble(sobol16(shuffled, d), g.dim[d]) ^ shift(dim));
    }

    /// Owen-scrambles the index: the first 2^m samples stay one aligned block of 2^m Sobol points
    /// (so they stay stratified), in a shuffled order. Scrambling flips a bit according to the
    /// bits above it, so for indices below 2^16 the upper half is one constant; dropping it XORs
    /// every point with one constant, which the Owen scramble of the point absorbs.
    static constexpr uint32_t shuffle(uint32_t index, uint32_t seed) {
        return sampler_detail::owen_scramble(index, seed) & 0xFFFFu;
    }

    static constexpr float to_unit(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

    const BlueNoiseMask* m_mask = nullptr;
    uint32_t m_x = 0, m_y = 0;
};

}  // namespace strata

#pragma once
// Deterministic per-pixel sample sequence: shuffled, Owen-scrambled Sobol points (Burley 2020,
// "Practical Hash-based Owen Scrambling", with Vegdahl's improved Laine-Karras hash).
//
// Sample `i` of pixel (x, y) in dimension `d` is a pure function of (x, y, i, d): it does not
// depend on the image size, the tile a pixel falls in, the thread that renders it or on how many
// samples were asked for. That is what makes frames byte-identical for the same inputs, and what
// makes accumulating two launches of k samples equal to one launch of 2k samples.
//
// Dimensions come in groups of four (one 4-D Sobol net each, "padded" with an independent seed
// per group): the first 2^m samples of a pixel are stratified in every group at 2^m strata.

#include <array>
#include <cstdint>

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

/// A well-mixed 32-bit hash (Wellons' lowbias32).
constexpr uint32_t hash_u32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

constexpr uint32_t hash_combine(uint32_t seed, uint32_t v) {
    return hash_u32(seed ^ (v + 0x9e3779b9u + (seed << 6) + (seed >> 2)));
}

/// The sample sequence of one pixel.
class PixelSampler {
public:
    /// Dimensions one group holds.
    static constexpr uint32_t GROUP = 4;
    /// Groups whose seeds are computed once, up front (the renderer uses two).
    static constexpr uint32_t CACHED_GROUPS = 2;
    /// Sample indices must be below this.
    static constexpr uint32_t MAX_SAMPLES = 1u << 16;

    constexpr PixelSampler() = default;
    constexpr PixelSampler(uint32_t x, uint32_t y)
        : m_seed(hash_combine(hash_combine(0x5eed5eedu, x), y)) {
        for (uint32_t g = 0; g < CACHED_GROUPS; ++g) m_groups[g] = seeds(g);
    }

    /// The 4-D point of sample `index` in dimension group `group`, each coordinate in [0, 1).
    constexpr std::array<float, 4> get4(uint32_t index, uint32_t group) const {
        const GroupSeeds g = group < CACHED_GROUPS ? m_groups[group] : seeds(group);
        const uint32_t shuffled = shuffle(index, g.index);
        std::array<float, 4> out{};
        for (uint32_t d = 0; d < 4; ++d) out[d] = coordinate(shuffled, d, g);
        return out;
    }

    /// Coordinate `dim` of sample `index` (dimension d is coordinate d % 4 of group d / 4).
    constexpr float get1(uint32_t index, uint32_t dim) const {
        const uint32_t group = dim / GROUP;
        const GroupSeeds g = group < CACHED_GROUPS ? m_groups[group] : seeds(group);
        return coordinate(shuffle(index, g.index), dim % GROUP, g);
    }

private:
    struct GroupSeeds {
        uint32_t index = 0;
        uint32_t dim[GROUP] = {};
    };

    constexpr GroupSeeds seeds(uint32_t group) const {
        GroupSeeds g;
        g.index = hash_combine(m_seed, group);
        for (uint32_t d = 0; d < GROUP; ++d) g.dim[d] = hash_combine(g.index, d + 1);
        return g;
    }

    static constexpr float coordinate(uint32_t shuffled, uint32_t d, const GroupSeeds& g) {
        using namespace sampler_detail;
        return to_unit(owen_scramble(sobol16(shuffled, d), g.dim[d]));
    }

    /// Owen-scrambles the index: the first 2^m samples stay one aligned block of 2^m Sobol points
    /// (so they stay stratified), in a per-pixel order. Scrambling flips a bit according to the
    /// bits above it, so for indices below 2^16 the upper half is one constant; dropping it XORs
    /// every point with one constant, which the Owen scramble of the point absorbs.
    static constexpr uint32_t shuffle(uint32_t index, uint32_t seed) {
        return sampler_detail::owen_scramble(index, seed) & 0xFFFFu;
    }

    static constexpr float to_unit(uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

    uint32_t m_seed = 0;
    GroupSeeds m_groups[CACHED_GROUPS] = {};
};

}  // namespace strata

#include "engine/render/blue_noise.h"

#include <vector>

#include "engine/render/sampler.h"

namespace strata {

namespace {

constexpr uint32_t N = BLUE_NOISE_SIZE;
constexpr uint32_t MASK = N - 1;
constexpr uint32_t P = BLUE_NOISE_PIXELS;
/// Pixels set before the first ranking: a tenth, as Ulichney suggests.
constexpr uint32_t INITIAL = P / 10;
/// The energy kernel reaches this many pixels each way (farther terms are under 1e-6).
constexpr int RADIUS = 8;
/// exp(-1 / (2 sigma^2)) for sigma 1.5: the kernel at squared distance k is Q^k, computed by
/// multiplication so that no libm routine (whose last bits vary by CPU) decides a rank.
constexpr double Q = 0.80073740291680804;

/// Each pixel's energy: the sum of the kernel over the set pixels, on the torus.
class Energy {
public:
    Energy() : m_energy(P, 0.0) {
        double power = 1.0;
        for (auto& k : m_kernel) k = 0.0;
        std::vector<double> powers(2 * RADIUS * RADIUS + 1);
        for (double& p : powers) {
            p = power;
            power *= Q;
        }
        for (int dy = -RADIUS; dy <= RADIUS; ++dy)
            for (int dx = -RADIUS; dx <= RADIUS; ++dx)
                m_kernel[std::size_t((dy + RADIUS) * (2 * RADIUS + 1) + dx + RADIUS)] =
                    powers[std::size_t(dx * dx + dy * dy)];
    }

    void add(uint32_t p, double sign) {
        const int px = int(p & MASK), py = int(p >> BLUE_NOISE_LOG2);
        for (int dy = -RADIUS; dy <= RADIUS; ++dy) {
            const uint32_t row = uint32_t(py + dy) & MASK;
            for (int dx = -RADIUS; dx <= RADIUS; ++dx) {
                const uint32_t q = row * N + (uint32_t(px + dx) & MASK);
                m_energy[q] +=
                    sign * m_kernel[std::size_t((dy + RADIUS) * (2 * RADIUS + 1) + dx + RADIUS)];
            }
        }
    }

    /// The set pixel of most energy (the tightest cluster) when `set`, else the unset pixel of
    /// least (the largest void); ties go to the lowest index.
    uint32_t extreme(const std::vector<uint8_t>& bits, bool set) const {
        uint32_t best = P;
        for (uint32_t p = 0; p < P; ++p) {
            if (bool(bits[p]) != set) continue;
            if (best == P || (set ? m_energy[p] > m_energy[best] : m_energy[p] < m_energy[best]))
                best = p;
        }
        return best;
    }

private:
    std::vector<double> m_energy;
    double m_kernel[(2 * RADIUS + 1) * (2 * RADIUS + 1)];
};

}  // namespace

BlueNoiseMask make_blue_noise_mask() {
    // Step: a random initial pattern, relaxed by moving the tightest cluster's pixel to the
    // largest void until that changes nothing.
    std::vector<uint8_t> bits(P, 0);
    Energy energy;
    for (uint32_t k = 0, placed = 0; placed < INITIAL; ++k) {
        const uint32_t p = hash_u32(k ^ 0xb1e5eedu) % P;
        if (bits[p]) continue;
        bits[p] = 1;
        energy.add(p, 1.0);
        ++placed;
    }
    for (uint32_t moves = 0; moves < P; ++moves) {
        const uint32_t cluster = energy.extreme(bits, true);
        bits[cluster] = 0;
        energy.add(cluster, -1.0);
        const uint32_t gap = energy.extreme(bits, false);
        bits[gap] = 1;
        energy.add(gap, 1.0);
        if (gap == cluster) break;
    }
    const std::vector<uint8_t> prototype = bits;
    const Energy prototype_energy = energy;

    // Step: the prototype's pixels ranked down from INITIAL - 1, tightest cluster first.
    BlueNoiseMask rank{};
    for (uint32_t r = INITIAL; r > 0; --r) {
        const uint32_t cluster = energy.extreme(bits, true);
        bits[cluster] = 0;
        energy.add(cluster, -1.0);
        rank[cluster] = uint16_t(r - 1);
    }
    // Step: the rest ranked up from INITIAL, largest void first. (Past half, Ulichney ranks the
    // tightest cluster of unset pixels; with a kernel whose sum is the same everywhere that is
    // the same pixel as the largest void of the set ones.)
    bits = prototype;
    energy = prototype_energy;
    for (uint32_t r = INITIAL; r < P; ++r) {
        const uint32_t gap = energy.extreme(bits, false);
        bits[gap] = 1;
        energy.add(gap, 1.0);
        rank[gap] = uint16_t(r);
    }
    return rank;
}

const BlueNoiseMask& blue_noise_mask() {
    static const BlueNoiseMask mask = make_blue_noise_mask();
    return mask;
}

}  // namespace strata

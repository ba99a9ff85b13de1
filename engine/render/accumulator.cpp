#include "engine/render/accumulator.h"

#include <algorithm>

namespace strata {

SampleRange Accumulator::begin(const AccumulationKey& key, uint32_t spp) {
    if (!m_key || !(*m_key == key)) {
        m_key.reset();
        m_sums.assign(std::size_t(key.width) * key.height, PixelSums{});
        m_samples = 0;
        m_key = key;
    }
    return {m_samples, std::min(spp, MAX_ACCUMULATED_SAMPLES - m_samples)};
}

void Accumulator::finish(const SampleRange& range) {
    m_samples = range.first + range.count;
}

void Accumulator::reset() {
    m_key.reset();
    m_samples = 0;
    m_sums.clear();
    m_sums.shrink_to_fit();
}

}  // namespace strata

#include "engine/image/highlight.h"

#include "engine/render/aov_buffers.h"

namespace strata {

std::size_t highlight_instance(uint8_t* rgb, const uint32_t* ids, uint32_t width, uint32_t height,
                               uint32_t slot) {
    if (slot == MISS_ID) return 0;
    std::size_t count = 0;
    for (uint32_t y = 0; y < height; ++y) {
        for (uint32_t x = 0; x < width; ++x) {
            const std::size_t i = std::size_t(y) * width + x;
            if (ids[i] != slot) continue;
            // An edge pixel: a 4-neighbour shows something else, or the frame ends there. The
            // neighbours are indexed from the frame's start (never a pointer moved backwards
            // past its row: UBSan's pointer-overflow check refuses that even when it wraps back).
            const bool edge = x == 0 || y == 0 || x + 1 == width || y + 1 == height ||
                              ids[i - 1] != slot || ids[i + 1] != slot || ids[i - width] != slot ||
                              ids[i + width] != slot;
            uint8_t* p = rgb + 3 * i;
            for (int c = 0; c < 3; ++c) {
                p[c] = edge ? HIGHLIGHT_RGB[c]
                            : uint8_t((p[c] * (256u - HIGHLIGHT_BLEND) +
                                       HIGHLIGHT_RGB[c] * HIGHLIGHT_BLEND + 128u) >>
                                      8);
            }
            ++count;
        }
    }
    return count;
}

}  // namespace strata

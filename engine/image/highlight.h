#pragma once
// The live viewer's selection highlight, drawn into an 8-bit frame from its instance_id AOV
// (aov_buffers.h): exactly the pixels whose id is the selected instance's slot change. Inside,
// the colour is blended towards HIGHLIGHT_RGB; the instance's own edge pixels (a 4-neighbour
// shows something else, or lies outside the frame) take HIGHLIGHT_RGB itself, an outline that
// stays visible on a surface of the highlight's own colour. Every other pixel keeps its bytes.

#include <cstddef>
#include <cstdint>

namespace strata {

/// The highlight colour (sRGB 8-bit): amber.
inline constexpr uint8_t HIGHLIGHT_RGB[3] = {255, 176, 32};
/// How far inner pixels move towards HIGHLIGHT_RGB, in 1/256.
inline constexpr unsigned HIGHLIGHT_BLEND = 104;

/// Tints the pixels of packed 8-bit RGB `rgb` (row-major from the top) whose `ids` entry is
/// `slot`; returns how many changed. `slot` MISS_ID tints nothing.
std::size_t highlight_instance(uint8_t* rgb, const uint32_t* ids, uint32_t width, uint32_t height,
                               uint32_t slot);

}  // namespace strata

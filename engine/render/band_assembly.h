#pragma once
// One frame from bands of rows rendered by several processes (server/split_render.h).
//
// A band (RenderRequest::band) holds exactly the floats the same rows of a whole render hold, and
// its EXR carries them at full precision (frame_encode.h). The assembling process reads each
// band's EXR back into buffers, places the bands, then finishes the frame the way a whole render
// finishes it: the filter over the assembled frame (it reads across band edges, so bands are
// rendered unfiltered with its guides), the guides dropped, and the ID manifest's names merged
// from the bands'. Encoding the result with encode_frame then gives the bytes of a whole render.

#include <cstdint>
#include <vector>

#include "engine/core/result.h"
#include "engine/image/exr.h"
#include "engine/render/aov_buffers.h"
#include "engine/render/frame.h"
#include "engine/render/render_request.h"

namespace strata {

/// The AOVs each band of `request` must carry: the requested ones plus, with `filter`, the
/// filter's guides (albedo, normal, depth).
AovSet band_aovs(const RenderRequest& request);

/// The request one band of `request` is rendered with: `band`, band_aovs(request), no filter,
/// EXR without compression (a band travels as its EXR).
RenderRequest band_request(const RenderRequest& request, RowBand band);

/// `count` bands covering `height` rows, as even as rows allow, each starting on a multiple of 4
/// rows where the height allows it (bands then trace no rows twice, renderer.cpp).
std::vector<RowBand> split_rows(uint32_t height, uint32_t count);

/// A band's pixels and the names its id channels stand for, read back from its EXR.
struct DecodedBand {
    FrameBuffers buffers;
    FrameIdNames names;
};

/// Reads a band's EXR: it must be `width` x `rows` and carry every channel of `aovs` with the
/// band encoding's types (beauty, albedo and normal FLOAT). The error says what is missing.
Result<DecodedBand> band_from_exr(const DecodedExr& exr, uint32_t width, uint32_t rows,
                                  AovSet aovs);

/// Collects the bands of one frame.
class FrameAssembly {
public:
    /// A width x height frame with the AOVs in `aovs` (band_aovs of the request).
    FrameAssembly(uint32_t width, uint32_t height, AovSet aovs);

    /// Copies `band` (its rows are [y0, y0 + band.height) of the frame) in; `names` are the
    /// names of its id channels. An error for a band of the wrong width, AOVs or rows.
    Status place(const FrameBuffers& band, uint32_t y0, const FrameIdNames& names);

    /// The frame of `request` (whose band_aovs the assembly holds): filtered when it asks for
    /// the filter, its guides dropped, the names merged. `camera` and `info` are the frame's
    /// (the camera of any band: all bands were traced with one). An error when rows are missing.
    Result<Frame> finish(const RenderRequest& request, const Camera& camera, FrameInfo info) &&;

private:
    FrameBuffers m_buffers;
    std::vector<bool> m_filled;  ///< per row
    FrameIdNames m_names;
};

}  // namespace strata

#pragma once
// The two frame types: a linear Frame (the buffers a launch wrote) and an EncodedFrame (the
// bytes a client receives). Both carry FrameInfo: the version the frame shows and the report of
// the commit its launch ran, so a caller never has to ask for that report separately.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/accel/report.h"
#include "engine/render/aov_buffers.h"

namespace strata {

/// How a frame was made.
struct FrameInfo {
    uint64_t version = 0;        ///< scene version the frame shows
    RebuildReport report;        ///< the commit the launch ran
    uint32_t samples = 0;        ///< samples per pixel in the frame (the total when accumulating)
    uint32_t samples_added = 0;  ///< samples per pixel this launch traced
    uint64_t rays = 0;           ///< rays traced (camera, shadow and bounce rays)
    double render_ms = 0.0;      ///< tracing and shading
};

/// The client ids that the slot numbers in a frame's `instance_id` and `mesh_id` buffers stand
/// for, at the frame's version: one (slot, id) pair per slot the buffer holds, sorted by slot.
/// Empty for an AOV the frame does not carry.
struct FrameIdNames {
    std::vector<std::pair<uint32_t, std::string>> instances;
    std::vector<std::pair<uint32_t, std::string>> meshes;
};

/// A frame's linear buffers.
struct Frame {
    FrameBuffers buffers;
    FrameInfo info;
    Camera camera;       ///< the camera the frame was traced with (the request's override applied)
    FrameIdNames names;  ///< for the EXR ID manifest
    /// The rows of the whole frame the buffers hold, when the request asked for a band.
    std::optional<RowBand> band;
    uint32_t frame_height = 0;  ///< the whole frame's height (the buffers' without a band)
};

/// A frame encoded for a client. The bytes are a std::string so that they move, uncopied, into
/// the HTTP response body.
struct EncodedFrame {
    std::string bytes;
    std::string content_type;  ///< "image/png", "image/x-exr" or "application/x-npz"
    FrameInfo info;
    double encode_ms = 0.0;
};

}  // namespace strata

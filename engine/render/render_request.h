#pragma once
// What a client asks a launch for, and what comes back. The names mirror the HTTP render request
// (width, height, format, spp, aovs, compression, accumulate, exposure, camera).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/cancel.h"
#include "engine/core/result.h"
#include "engine/image/exr.h"
#include "engine/scene/edits.h"
#include "engine/scene/types.h"

namespace strata {

/// PNG: the tone-mapped beauty image. EXR: linear, with AOVs. NPZ: the same arrays as numpy
/// reads them (frame_encode.h).
enum class ImageFormat : uint8_t { Png, Exr, Npz };

/// Arbitrary output variables a frame can carry besides the beauty image.
enum class Aov : uint8_t {
    Color,
    Albedo,
    Normal,
    Depth,
    Position,
    InstanceId,
    PrimitiveId,
    MeshId,
    UserId
};

/// Wire names: "png"/"exr"/"npz", "none"/"zip"/"piz", "color", "albedo", "normal", "depth", "position",
/// "instance_id", "primitive_id", "mesh_id", "user_id".
const char* image_format_name(ImageFormat f);
const char* exr_compression_name(ExrCompression c);
const char* aov_name(Aov a);
std::optional<ImageFormat> parse_image_format(std::string_view s);
std::optional<ExrCompression> parse_exr_compression(std::string_view s);
std::optional<Aov> parse_aov(std::string_view s);

/// Rows [y0, y0 + rows) of a frame: the part of it one process renders when a frame is split
/// across processes (server/split_render.h).
struct RowBand {
    uint32_t y0 = 0;
    uint32_t rows = 0;
    friend bool operator==(const RowBand&, const RowBand&) = default;
};

/// One frame to render. renderer.h, aov_buffers.h, frame_encode.h, accumulator.h and tonemap.h
/// give the details of each field's effect.
struct RenderRequest {
    uint32_t width = 640;
    uint32_t height = 360;
    ImageFormat format = ImageFormat::Png;
    /// Samples per pixel this launch traces (each pixel has its own fixed sample sequence).
    uint32_t spp = 1;
    /// Extra layers (EXR only; "color" is the beauty image, always included, so it may be listed
    /// with PNG too).
    std::vector<Aov> aovs;
    ExrCompression compression = ExrCompression::Zip;  ///< EXR only
    /// Add spp samples to the previous accumulating launch of the same scene version, camera and
    /// size instead of starting over.
    bool accumulate = false;
    float exposure = 0.0f;  ///< EV stops applied before tone mapping (PNG only; EXR is linear)
    /// Smooth the colour with the edge-aware filter of aov_filter.h (guided by albedo, normal
    /// and depth, which the launch then computes even when not asked for). Off by default.
    bool filter = false;
    /// Overrides the scene camera for this frame. Fields it leaves out come from the scene
    /// camera of the version the launch renders, so the frame never mixes two versions.
    std::optional<SetCamera> camera;
    /// Renders only these rows of the width x height frame: every pixel's samples, camera rays
    /// and sample sequence are those of the whole frame, so the band is bit for bit the same rows
    /// of a whole render. The frame's buffers then hold `rows` rows. Not with `accumulate` (the
    /// sums belong to whole frames) or `filter` (it reads neighbours across the band's edges:
    /// a caller assembling bands filters the assembled frame, renderer.h).
    std::optional<RowBand> band;
    /// Shows the animated instances at this scene time instead of the scene's (Timeline): the
    /// scene is not changed, and the next launch without one shows the scene's time again.
    std::optional<float> time;
    /// Not part of what a client asks: the caller's stop flag (deadline, client gone, shutdown),
    /// polled between packets. A cancelled launch returns ErrorCode::Cancelled.
    const CancelToken* cancel = nullptr;
};

/// The camera a launch renders: the scene camera with the request's override applied, checked
/// (an error names the field as "camera/<field>").
Result<Camera> resolve_camera(const std::optional<SetCamera>& override_fields, const Camera& scene);

/// Largest frame the engine renders in one launch (the server may set a lower cap).
constexpr uint64_t MAX_RENDER_PIXELS = 64ull * 1024 * 1024;
constexpr uint32_t MAX_RENDER_SPP = 4096;

/// Checks a request (sizes, spp, exposure, camera override, duplicate AOVs, AOVs other than color
/// with PNG, a band outside the frame or with accumulate or filter); the error names the field.
Status check_render_request(const RenderRequest& r);

}  // namespace strata

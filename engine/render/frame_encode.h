#pragma once
// Turns a rendered frame into the bytes a client asked for.
//
// PNG: the beauty image through exposure, ACES tone mapping and the sRGB curve (tonemap.h) as
// 8-bit RGB; AOVs cannot be carried (check_render_request refuses them).
//
// EXR: linear, no exposure. Channels, with OpenEXR's layer naming:
//   beauty        R, G, B (half), A (half, 1: the sky is part of the image)
//   albedo        albedo.R, albedo.G, albedo.B (half)
//   normal        N.X, N.Y, N.Z (half)
//   depth         Z (float; +inf where nothing was hit)
//   position      P.X, P.Y, P.Z (float)
//   instance_id   instance_id (uint; 0xFFFFFFFF where nothing was hit)
//   primitive_id  primitive_id (uint)
//   mesh_id       mesh_id (uint)
//   user_id       user_id (uint)
// A band (RenderRequest::band) is written at full precision instead: beauty, albedo and normal
// as FLOAT, so that a process assembling bands (band_assembly.h) gets the very floats a whole
// render would encode. Compression as requested (default zip). The header carries OpenEXR's
// standard worldToCamera and
// worldToNDC for the frame's camera (camera_rays.h) and, with instance_id or mesh_id, an ID
// manifest naming every slot the channels hold with its client id (component "instance" or
// "mesh", lifetime frame: a freed slot may name another object in a later frame).
//
// NPZ (npz.h): the same content for numpy alone, linear and at full precision: `beauty`,
// `albedo`, `normal`, `position` float32 (height, width, 3), `depth` float32 (height, width), the
// id AOVs uint32 (height, width) under their AOV names, and each ID manifest as `<aov>.ids`
// (uint32) beside `<aov>.names` (unicode): the client id of value ids[k] is names[k].

#include <cstdint>
#include <vector>

#include "engine/core/result.h"
#include "engine/image/exr.h"
#include "engine/render/aov_buffers.h"
#include "engine/render/frame.h"
#include "engine/render/render_request.h"

namespace strata {

/// Encodes `buffers` in `request`'s format with its exposure, AOVs and compression, and (EXR and
/// NPZ) `attributes`; the result carries the encoding time (its `info` is the caller's to fill in).
Result<EncodedFrame> encode_frame(const FrameBuffers& buffers, const RenderRequest& request,
                                  const ExrAttributes& attributes = {});

/// The EXR header attributes of `frame`: camera matrices and the ID manifest.
ExrAttributes exr_attributes(const Frame& frame);

/// The EXR channels of `frame`: beauty and every AOV the frame carries; with `full_precision`
/// beauty, albedo and normal are FLOAT rather than HALF (a band's encoding).
std::vector<ExrChannel> exr_channels(const FrameBuffers& frame, bool full_precision = false);

}  // namespace strata

#include "engine/render/frame_encode.h"

#include <new>

#include "engine/core/timer.h"
#include "engine/image/npz.h"
#include "engine/image/png.h"
#include "engine/image/tonemap.h"
#include "engine/render/camera_rays.h"

namespace strata {

namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 buffers are read as packed floats");

const float ONE = 1.0f;

void add_vec3(std::vector<ExrChannel>& out, const std::vector<Vec3>& buffer, const char* layer,
              const char* const (&suffixes)[3], ExrPixel type) {
    const float* base = &buffer.data()->x;
    for (int k = 0; k < 3; ++k) {
        const std::string name = layer[0] ? std::string(layer) + "." + suffixes[k] : suffixes[k];
        out.push_back(ExrChannel{name, type, base + k, nullptr, 3});
    }
}

void add_uint(std::vector<ExrChannel>& out, const std::vector<uint32_t>& buffer, Aov aov) {
    out.push_back(ExrChannel{aov_name(aov), ExrPixel::Uint, nullptr, buffer.data(), 1});
}

std::string_view bytes_of(const void* data, std::size_t n) {
    return {static_cast<const char*>(data), n};
}

/// The frame as numpy arrays: what exr_channels writes, one array per AOV, full precision, and
/// each ID manifest table as `<aov>.ids` (uint32) beside `<aov>.names` (unicode).
Result<std::string> encode_arrays(const FrameBuffers& f, const ExrAttributes& attributes) {
    const std::size_t h = f.height, w = f.width, n = f.pixel_count();
    std::vector<NpyArray> arrays;
    auto vec3 = [&](const char* name, const std::vector<Vec3>& b) {
        arrays.push_back({name, "<f4", {h, w, 3}, bytes_of(b.data(), n * sizeof(Vec3))});
    };
    auto u32 = [&](Aov aov, const std::vector<uint32_t>& b) {
        arrays.push_back({aov_name(aov), "<u4", {h, w}, bytes_of(b.data(), n * 4)});
    };
    vec3("beauty", f.color);
    if (f.aovs.has(Aov::Albedo)) vec3("albedo", f.albedo);
    if (f.aovs.has(Aov::Normal)) vec3("normal", f.normal);
    if (f.aovs.has(Aov::Depth))
        arrays.push_back({"depth", "<f4", {h, w}, bytes_of(f.depth.data(), n * 4)});
    if (f.aovs.has(Aov::Position)) vec3("position", f.position);
    if (f.aovs.has(Aov::InstanceId)) u32(Aov::InstanceId, f.instance_id);
    if (f.aovs.has(Aov::PrimitiveId)) u32(Aov::PrimitiveId, f.primitive_id);
    if (f.aovs.has(Aov::MeshId)) u32(Aov::MeshId, f.mesh_id);
    if (f.aovs.has(Aov::UserId)) u32(Aov::UserId, f.user_id);
    // The manifests' storage outlives `arrays`, which borrows it.
    std::vector<std::vector<uint32_t>> ids(attributes.ids.size()), names(attributes.ids.size());
    for (std::size_t t = 0; t < attributes.ids.size(); ++t) {
        const ExrIdTable& table = attributes.ids[t];
        std::vector<std::string> texts;
        for (const auto& [id, text] : table.entries) {
            ids[t].push_back(id);
            texts.push_back(text);
        }
        const std::string dtype = utf32_array(texts, names[t]);
        const std::size_t count = table.entries.size();
        arrays.push_back({table.channel + ".ids", "<u4", {count}, bytes_of(ids[t].data(), count * 4)});
        arrays.push_back({table.channel + ".names", dtype, {count},
                          bytes_of(names[t].data(), names[t].size() * 4)});
    }
    return encode_npz(arrays);
}

}  // namespace

std::vector<ExrChannel> exr_channels(const FrameBuffers& f, bool full_precision) {
    static const char* const RGB[3] = {"R", "G", "B"};
    static const char* const XYZ[3] = {"X", "Y", "Z"};
    const ExrPixel colour = full_precision ? ExrPixel::Float : ExrPixel::Half;
    std::vector<ExrChannel> channels;
    add_vec3(channels, f.color, "", RGB, colour);
    channels.push_back(ExrChannel{"A", ExrPixel::Half, &ONE, nullptr, 0});
    if (f.aovs.has(Aov::Albedo)) add_vec3(channels, f.albedo, "albedo", RGB, colour);
    if (f.aovs.has(Aov::Normal)) add_vec3(channels, f.normal, "N", XYZ, colour);
    if (f.aovs.has(Aov::Depth))
        channels.push_back(ExrChannel{"Z", ExrPixel::Float, f.depth.data(), nullptr, 1});
    if (f.aovs.has(Aov::Position)) add_vec3(channels, f.position, "P", XYZ, ExrPixel::Float);
    if (f.aovs.has(Aov::InstanceId)) add_uint(channels, f.instance_id, Aov::InstanceId);
    if (f.aovs.has(Aov::PrimitiveId)) add_uint(channels, f.primitive_id, Aov::PrimitiveId);
    if (f.aovs.has(Aov::MeshId)) add_uint(channels, f.mesh_id, Aov::MeshId);
    if (f.aovs.has(Aov::UserId)) add_uint(channels, f.user_id, Aov::UserId);
    return channels;
}

ExrAttributes exr_attributes(const Frame& frame) {
    ExrAttributes a;
    a.world_to_camera = world_to_camera(frame.camera);
    // A band's matrices are those of the whole frame it is part of.
    const uint32_t height = frame.band ? frame.frame_height : frame.buffers.height;
    a.world_to_ndc = world_to_ndc(frame.camera, frame.buffers.width, height);
    if (frame.buffers.aovs.has(Aov::InstanceId))
        a.ids.push_back({aov_name(Aov::InstanceId), "instance", frame.names.instances});
    if (frame.buffers.aovs.has(Aov::MeshId))
        a.ids.push_back({aov_name(Aov::MeshId), "mesh", frame.names.meshes});
    return a;
}

Result<EncodedFrame> encode_frame(const FrameBuffers& buffers, const RenderRequest& request,
                                  const ExrAttributes& attributes) {
    Stopwatch clock;
    EncodedFrame out;
    if (request.format == ImageFormat::Exr) {
        auto exr = encode_exr(buffers.width, buffers.height,
                              exr_channels(buffers, request.band.has_value()),
                              request.compression, attributes);
        if (!exr) return Unexpected(exr.error());
        out.bytes = std::move(exr.value());
        out.content_type = "image/x-exr";
    } else if (request.format == ImageFormat::Npz) {
        auto npz = encode_arrays(buffers, attributes);
        if (!npz) return Unexpected(npz.error());
        out.bytes = std::move(npz.value());
        out.content_type = "application/x-npz";
    } else {
        try {
            std::vector<uint8_t> rgb(buffers.pixel_count() * 3);
            tonemap_to_srgb8(buffers.color.data(), buffers.pixel_count(), request.exposure,
                             rgb.data());
            auto png = encode_png(rgb.data(), buffers.width, buffers.height, 3);
            if (!png) return Unexpected(png.error());
            out.bytes = std::move(png.value());
        } catch (const std::bad_alloc&) {
            return failure(ErrorCode::TooLarge, "not enough memory to encode the frame", "width");
        }
        out.content_type = "image/png";
    }
    out.encode_ms = clock.ms();
    return out;
}

}  // namespace strata

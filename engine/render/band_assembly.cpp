#include "engine/render/band_assembly.h"

#include <algorithm>
#include <cstring>
#include <new>
#include <string>
#include <type_traits>

#include "engine/render/aov_filter.h"

namespace strata {

namespace {

constexpr uint32_t BAND_ALIGN = 4;  // PACKET_SIZE (tiles.h): bands that share no packet row

/// Calls `f(aov, buffer)` for every buffer of `b` that `set` holds, beauty first.
template <class Buffers, class F>
void for_each_buffer(Buffers& b, AovSet set, F&& f) {
    f(Aov::Color, b.color);
    if (set.has(Aov::Albedo)) f(Aov::Albedo, b.albedo);
    if (set.has(Aov::Normal)) f(Aov::Normal, b.normal);
    if (set.has(Aov::Depth)) f(Aov::Depth, b.depth);
    if (set.has(Aov::Position)) f(Aov::Position, b.position);
    if (set.has(Aov::InstanceId)) f(Aov::InstanceId, b.instance_id);
    if (set.has(Aov::PrimitiveId)) f(Aov::PrimitiveId, b.primitive_id);
    if (set.has(Aov::MeshId)) f(Aov::MeshId, b.mesh_id);
    if (set.has(Aov::UserId)) f(Aov::UserId, b.user_id);
}

/// (slot, name) pairs of `a` and `b` together, sorted by slot, each slot once.
void merge_names(std::vector<std::pair<uint32_t, std::string>>& into,
                 const std::vector<std::pair<uint32_t, std::string>>& more) {
    into.insert(into.end(), more.begin(), more.end());
    std::stable_sort(into.begin(), into.end(),
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    into.erase(std::unique(into.begin(), into.end(),
                           [](const auto& x, const auto& y) { return x.first == y.first; }),
               into.end());
}

/// Reads the float channels `names` (one per component) of `exr` into a Vec3 or float buffer.
template <class T>
Status read_floats(const DecodedExr& exr, std::initializer_list<const char*> names, ExrPixel type,
                   std::vector<T>& out, std::size_t n) {
    out.resize(n);
    float* dst = reinterpret_cast<float*>(out.data());
    const std::size_t stride = names.size();
    std::size_t k = 0;
    for (const char* name : names) {
        const DecodedExrChannel* c = exr.find(name);
        if (!c || c->type != type || c->f32.size() != n)
            return failure(ErrorCode::InvalidArgument,
                           std::string("the band's EXR has no ") +
                               (type == ExrPixel::Float ? "FLOAT" : "HALF") + " channel '" + name +
                               "' of its size",
                           "band");
        for (std::size_t i = 0; i < n; ++i) dst[i * stride + k] = c->f32[i];
        ++k;
    }
    return {};
}

Status read_uints(const DecodedExr& exr, Aov aov, std::vector<uint32_t>& out, std::size_t n) {
    const DecodedExrChannel* c = exr.find(aov_name(aov));
    if (!c || c->type != ExrPixel::Uint || c->u32.size() != n)
        return failure(
            ErrorCode::InvalidArgument,
            std::string("the band's EXR has no UINT channel '") + aov_name(aov) + "' of its size",
            "band");
    out = c->u32;
    return {};
}

std::vector<std::pair<uint32_t, std::string>> table_of(const DecodedExr& exr, Aov aov) {
    for (const ExrIdTable& t : exr.ids)
        if (t.channel == aov_name(aov)) return t.entries;
    return {};
}

}  // namespace

AovSet band_aovs(const RenderRequest& request) {
    AovSet set(request.aovs);
    if (request.filter) {
        set.add(Aov::Albedo);
        set.add(Aov::Normal);
        set.add(Aov::Depth);
    }
    return set;
}

RenderRequest band_request(const RenderRequest& request, RowBand band) {
    RenderRequest r = request;
    r.band = band;
    r.filter = false;
    r.format = ImageFormat::Exr;
    r.compression = ExrCompression::None;
    r.aovs.clear();
    const AovSet set = band_aovs(request);
    for (uint32_t a = 0; a <= uint32_t(Aov::UserId); ++a) {
        if (set.has(Aov(a))) r.aovs.push_back(Aov(a));
    }
    return r;
}

std::vector<RowBand> split_rows(uint32_t height, uint32_t count) {
    std::vector<RowBand> bands;
    if (count == 0 || count > height) return bands;
    std::vector<uint32_t> edges{0};
    bool aligned = true;
    for (uint32_t k = 1; k < count; ++k) {
        const uint32_t even = uint32_t(uint64_t(k) * height / count);
        const uint32_t edge = even / BAND_ALIGN * BAND_ALIGN;
        if (edge <= edges.back()) aligned = false;
        edges.push_back(edge);
    }
    if (!aligned || height <= edges.back()) {
        // Too few rows to align: even bands (still exact, they trace a few rows twice).
        for (uint32_t k = 1; k < count; ++k) edges[k] = uint32_t(uint64_t(k) * height / count);
    }
    edges.push_back(height);
    for (uint32_t k = 0; k < count; ++k) bands.push_back({edges[k], edges[k + 1] - edges[k]});
    return bands;
}

Result<DecodedBand> band_from_exr(const DecodedExr& exr, uint32_t width, uint32_t rows,
                                  AovSet aovs) {
    if (exr.width != width || exr.height != rows)
        return failure(ErrorCode::InvalidArgument,
                       "the band's EXR is " + std::to_string(exr.width) + "x" +
                           std::to_string(exr.height) + ", not " + std::to_string(width) + "x" +
                           std::to_string(rows),
                       "band");
    DecodedBand out;
    FrameBuffers& b = out.buffers;
    b.width = width;
    b.height = rows;
    b.aovs = aovs;
    const std::size_t n = b.pixel_count();
    try {
        Status s = read_floats(exr, {"R", "G", "B"}, ExrPixel::Float, b.color, n);
        if (s && aovs.has(Aov::Albedo))
            s = read_floats(exr, {"albedo.R", "albedo.G", "albedo.B"}, ExrPixel::Float, b.albedo,
                            n);
        if (s && aovs.has(Aov::Normal))
            s = read_floats(exr, {"N.X", "N.Y", "N.Z"}, ExrPixel::Float, b.normal, n);
        if (s && aovs.has(Aov::Depth)) s = read_floats(exr, {"Z"}, ExrPixel::Float, b.depth, n);
        if (s && aovs.has(Aov::Position))
            s = read_floats(exr, {"P.X", "P.Y", "P.Z"}, ExrPixel::Float, b.position, n);
        if (s && aovs.has(Aov::InstanceId)) s = read_uints(exr, Aov::InstanceId, b.instance_id, n);
        if (s && aovs.has(Aov::PrimitiveId))
            s = read_uints(exr, Aov::PrimitiveId, b.primitive_id, n);
        if (s && aovs.has(Aov::MeshId)) s = read_uints(exr, Aov::MeshId, b.mesh_id, n);
        if (s && aovs.has(Aov::UserId)) s = read_uints(exr, Aov::UserId, b.user_id, n);
        if (!s) return Unexpected(s.error());
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory for the band", "band");
    }
    if (aovs.has(Aov::InstanceId)) out.names.instances = table_of(exr, Aov::InstanceId);
    if (aovs.has(Aov::MeshId)) out.names.meshes = table_of(exr, Aov::MeshId);
    return out;
}

FrameAssembly::FrameAssembly(uint32_t width, uint32_t height, AovSet aovs)
    : m_filled(height, false) {
    m_buffers.allocate(width, height, aovs);
}

Status FrameAssembly::place(const FrameBuffers& band, uint32_t y0, const FrameIdNames& names) {
    if (band.width != m_buffers.width || !(band.aovs == m_buffers.aovs) || band.height == 0 ||
        y0 >= m_buffers.height || band.height > m_buffers.height - y0)
        return failure(ErrorCode::InvalidArgument,
                       "a band of " + std::to_string(band.width) + "x" +
                           std::to_string(band.height) + " at row " + std::to_string(y0) +
                           " does not fit the frame's rows and AOVs",
                       "band");
    const std::size_t offset = std::size_t(y0) * m_buffers.width;
    const std::size_t n = band.pixel_count();
    bool sizes_ok = true;
    for_each_buffer(m_buffers, m_buffers.aovs, [&](Aov a, auto& dst) {
        for_each_buffer(band, band.aovs, [&](Aov b, const auto& src) {
            if constexpr (std::is_same_v<std::decay_t<decltype(dst)>,
                                         std::decay_t<decltype(src)>>) {
                if (a != b) return;
                if (src.size() != n) {
                    sizes_ok = false;
                    return;
                }
                std::copy(src.begin(), src.end(), dst.begin() + std::ptrdiff_t(offset));
            }
        });
    });
    if (!sizes_ok)
        return failure(ErrorCode::InvalidArgument, "a band's buffers are not of its size", "band");
    std::fill(m_filled.begin() + y0, m_filled.begin() + y0 + band.height, true);
    merge_names(m_names.instances, names.instances);
    merge_names(m_names.meshes, names.meshes);
    return {};
}

Result<Frame> FrameAssembly::finish(const RenderRequest& request, const Camera& camera,
                                    FrameInfo info) && {
    const auto missing = std::find(m_filled.begin(), m_filled.end(), false);
    if (missing != m_filled.end())
        return failure(
            ErrorCode::Internal,
            "row " + std::to_string(missing - m_filled.begin()) + " of the frame came from no band",
            "band");
    if (request.filter) {
        try {
            filter_frame(m_buffers);
        } catch (const std::bad_alloc&) {
            return failure(ErrorCode::TooLarge, "not enough memory to filter the frame", "width");
        }
    }
    m_buffers.keep_only(AovSet(request.aovs));
    Frame frame;
    frame.buffers = std::move(m_buffers);
    frame.info = std::move(info);
    frame.camera = camera;
    frame.frame_height = frame.buffers.height;
    if (frame.buffers.aovs.has(Aov::InstanceId))
        frame.names.instances = std::move(m_names.instances);
    if (frame.buffers.aovs.has(Aov::MeshId)) frame.names.meshes = std::move(m_names.meshes);
    return frame;
}

}  // namespace strata

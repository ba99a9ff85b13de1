#include "engine/render/render_request.h"

#include <algorithm>
#include <cmath>

#include "engine/scene/animation.h"

namespace strata {

namespace {

constexpr const char* FORMAT_NAMES[] = {"png", "exr", "npz"};
constexpr const char* COMPRESSION_NAMES[] = {"none", "zip", "piz"};
constexpr const char* AOV_NAMES[] = {"color",       "albedo",       "normal",  "depth",  "position",
                                     "instance_id", "primitive_id", "mesh_id", "user_id"};

template <class E, std::size_t N>
std::optional<E> parse_name(const char* const (&names)[N], std::string_view s) {
    for (std::size_t i = 0; i < N; ++i) {
        if (s == names[i]) return static_cast<E>(i);
    }
    return std::nullopt;
}

}  // namespace

const char* image_format_name(ImageFormat f) {
    return FORMAT_NAMES[int(f)];
}
const char* exr_compression_name(ExrCompression c) {
    return COMPRESSION_NAMES[int(c)];
}
const char* aov_name(Aov a) {
    return AOV_NAMES[int(a)];
}
std::optional<ImageFormat> parse_image_format(std::string_view s) {
    return parse_name<ImageFormat>(FORMAT_NAMES, s);
}
std::optional<ExrCompression> parse_exr_compression(std::string_view s) {
    return parse_name<ExrCompression>(COMPRESSION_NAMES, s);
}
std::optional<Aov> parse_aov(std::string_view s) {
    return parse_name<Aov>(AOV_NAMES, s);
}

Status check_render_request(const RenderRequest& r) {
    if (r.width == 0 || r.height == 0)
        return failure(ErrorCode::InvalidArgument, "width and height must be at least 1",
                       r.width == 0 ? "width" : "height");
    if (uint64_t(r.width) * r.height > MAX_RENDER_PIXELS)
        return failure(ErrorCode::TooLarge,
                       "frame has " + std::to_string(uint64_t(r.width) * r.height) +
                           " pixels; the limit is " + std::to_string(MAX_RENDER_PIXELS),
                       "width");
    if (r.spp == 0 || r.spp > MAX_RENDER_SPP)
        return failure(ErrorCode::InvalidArgument,
                       "spp must be in [1, " + std::to_string(MAX_RENDER_SPP) + "]", "spp");
    if (Status s = check_launch_time(r.time); !s) return s;
    if (!std::isfinite(r.exposure) || std::abs(r.exposure) > 64.0f)
        return failure(ErrorCode::InvalidArgument,
                       "exposure must be a finite number of stops in [-64, 64]", "exposure");
    for (std::size_t i = 0; i < r.aovs.size(); ++i) {
        if (std::count(r.aovs.begin(), r.aovs.end(), r.aovs[i]) > 1)
            return failure(ErrorCode::InvalidArgument,
                           std::string("AOV '") + aov_name(r.aovs[i]) + "' is listed twice",
                           "aovs/" + std::to_string(i));
        if (r.format == ImageFormat::Png && r.aovs[i] != Aov::Color)
            return failure(ErrorCode::InvalidArgument,
                           std::string("AOV '") + aov_name(r.aovs[i]) +
                               "' needs format exr or npz; a PNG carries only the color image",
                           "aovs/" + std::to_string(i));
    }
    if (r.band) {
        const RowBand& b = *r.band;
        if (b.rows == 0 || b.y0 >= r.height || b.rows > r.height - b.y0)
            return failure(ErrorCode::InvalidArgument,
                           "band rows [" + std::to_string(b.y0) + ", " +
                               std::to_string(uint64_t(b.y0) + b.rows) +
                               ") must be a non-empty range inside the frame's " +
                               std::to_string(r.height) + " rows",
                           "band");
        if (r.accumulate)
            return failure(ErrorCode::InvalidArgument,
                           "a band cannot accumulate: accumulated sums belong to whole frames",
                           "band");
        if (r.filter)
            return failure(ErrorCode::InvalidArgument,
                           "a band cannot be filtered: the filter reads pixels beyond the band's "
                           "edges (filter the assembled frame)",
                           "band");
    }
    if (r.camera) {
        // What can be judged without the scene camera: the override's own numbers.
        const SetCamera& c = *r.camera;
        for (const auto& [name, v] :
             {std::pair{"eye", c.eye}, {"target", c.target}, {"up", c.up}}) {
            if (v && !is_finite(*v))
                return failure(ErrorCode::NotFinite,
                               std::string(name) + " has a NaN or infinite value",
                               std::string("camera/") + name);
        }
        if (c.fov_y_deg && !(*c.fov_y_deg > 0.0f && *c.fov_y_deg < 180.0f))
            return failure(ErrorCode::InvalidArgument, "fov_y_deg must be in (0, 180)",
                           "camera/fov_y_deg");
    }
    return {};
}

Result<Camera> resolve_camera(const std::optional<SetCamera>& override_fields,
                              const Camera& scene) {
    Camera c = scene;
    if (!override_fields) return c;
    apply_to(c, *override_fields);
    if (Status s = check_camera(c); !s) {
        Error e = s.error();
        e.field = "camera/" + e.field;
        return Unexpected(e);
    }
    return c;
}

}  // namespace strata

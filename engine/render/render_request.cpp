#include "engine/render/render_request.h"

#include <algorithm>
#include <cmath>

namespace strata {

namespace {

constexpr const char* FORMAT_NAMES[] = {"png", "exr"};
constexpr const char* COMPRESSION_NAMES[] = {"none", "zip", "piz"};
constexpr const char* AOV_NAMES[] = {"color",    "albedo",      "normal",       "depth",
                                     "position", "instance_id", "primitive_id", "mesh_id"};

template <class E, std::size_t N>
std::optional<E> parse_name(const char* const (&names)[N], std::string_view s) {
    for (std::size_t i = 0; i < N; ++i) {
        if (s == names[i]) return static_cast<E>(i);
    }
    return std::nullopt;
}

}  // namespace

const char* image_format_name(ImageFormat f) { return FORMAT_NAMES[int(f)]; }
const char* exr_compression_name(ExrCompression c) { return COMPRESSION_NAMES[int(c)]; }
const char* aov_name(Aov a) { return AOV_NAMES[int(a)]; }
std::optional<ImageFormat> parse_image_format(std::string_view s) {
    return parse_name<ImageFormat>(FORMAT_NAMES, s);
}
std::optional<ExrCompression> parse_exr_compression(std::string_view s) {
    return parse_name<ExrCompression>(COMPRESSION_NAMES, s);
}
std::optional<Aov> parse_aov(std::string_view s) { return parse_name<Aov>(AOV_NAMES, s); }

Status check_render_request(const RenderRequest& r) {
    if (r.width == 0 || r.height == 0)
        return make_error(ErrorCode::InvalidArgument, "width and height must be at least 1",
                          r.width == 0 ? "width" : "height");
    if (uint64_t(r.width) * r.height > MAX_RENDER_PIXELS)
        return make_error(ErrorCode::TooLarge,
                          "frame has " + std::to_string(uint64_t(r.width) * r.height) +
                              " pixels; the limit is " + std::to_string(MAX_RENDER_PIXELS),
                          "width");
    if (r.spp == 0 || r.spp > MAX_RENDER_SPP)
        return make_error(ErrorCode::InvalidArgument,
                          "spp must be in [1, " + std::to_string(MAX_RENDER_SPP) + "]", "spp");
    if (!std::isfinite(r.exposure) || std::abs(r.exposure) > 64.0f)
        return make_error(ErrorCode::InvalidArgument, "exposure must be a finite number of stops in [-64, 64]",
                          "exposure");
    for (std::size_t i = 0; i < r.aovs.size(); ++i) {
        if (std::count(r.aovs.begin(), r.aovs.end(), r.aovs[i]) > 1)
            return make_error(ErrorCode::InvalidArgument,
                              std::string("AOV '") + aov_name(r.aovs[i]) + "' is listed twice",
                              "aovs/" + std::to_string(i));
        if (r.format == ImageFormat::Png && r.aovs[i] != Aov::Color)
            return make_error(ErrorCode::InvalidArgument,
                              std::string("AOV '") + aov_name(r.aovs[i]) +
                                  "' needs format exr; a PNG carries only the color image",
                              "aovs/" + std::to_string(i));
    }
    if (r.camera) {
        if (Status s = check_camera(*r.camera); !s) {
            Error e = s.error();
            e.field = "camera/" + e.field;
            return e;
        }
    }
    return {};
}

}  // namespace strata

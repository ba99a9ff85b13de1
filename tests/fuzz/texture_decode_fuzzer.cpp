// libFuzzer target for the texture decoder (engine/image/texture_decode.h): untrusted PNG and
// JPEG bytes through libpng and libturbojpeg, then lookups over the decoded texels with every
// wrap mode and filter. The limits are small so that a header claiming a huge image is refused
// rather than allocated (the same path the scene's budget takes).

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "engine/image/texture_decode.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata;
    TextureLimits limits;
    limits.max_side = 4096;
    limits.max_bytes = uint64_t(32) << 20;
    auto image =
        decode_texture(std::string_view(reinterpret_cast<const char*>(data), size), limits);
    if (!image) return 0;
    const TextureImage& t = image.value();
    if (t.width == 0 || t.height == 0 || t.texels.size() != std::size_t(t.width) * t.height * 3)
        __builtin_trap();  // a decoded image always has its texels
    float sum = 0.0f;
    for (TextureWrap w : {TextureWrap::Repeat, TextureWrap::Clamp, TextureWrap::Mirror}) {
        for (TextureFilter f : {TextureFilter::Bilinear, TextureFilter::Nearest}) {
            for (Vec2 uv : {Vec2(0.0f), Vec2(0.999f), Vec2(-1.5f, 2.25f), Vec2(1e7f, -1e7f)}) {
                const Vec3 c = t.sample(uv, TextureSampler{w, f});
                sum += c.x + c.y + c.z;
            }
        }
    }
    if (!(sum >= 0.0f)) __builtin_trap();  // texels are in [0, 1]: never NaN or negative
    return 0;
}

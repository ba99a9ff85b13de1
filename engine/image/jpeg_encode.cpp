#include "engine/image/jpeg_encode.h"

#include <turbojpeg.h>

#include <memory>
#include <new>
#include <vector>

#include "engine/image/tonemap.h"

namespace strata {

Result<std::string> encode_jpeg(const uint8_t* rgb, uint32_t width, uint32_t height, int quality) {
    if (width == 0 || height == 0)
        return failure(ErrorCode::InvalidArgument, "a JPEG needs at least one pixel", "width");
    if (quality < 1 || quality > 100)
        return failure(ErrorCode::InvalidArgument,
                       "JPEG quality must be in 1..100, not " + std::to_string(quality), "quality");
    std::unique_ptr<void, int (*)(tjhandle)> handle(tjInitCompress(), tjDestroy);
    if (!handle) return failure(ErrorCode::Internal, "cannot start the JPEG encoder");
    unsigned char* out = nullptr;
    unsigned long size = 0;
    const int rc = tjCompress2(handle.get(), rgb, int(width), 0, int(height), TJPF_RGB, &out, &size,
                               TJSAMP_420, quality, TJFLAG_FASTDCT);
    std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(out, tjFree);
    if (rc != 0)
        return failure(ErrorCode::Internal,
                       std::string("JPEG encoding failed: ") + tjGetErrorStr2(handle.get()));
    return std::string(reinterpret_cast<const char*>(out), size);
}

Result<std::string> encode_jpeg_linear(const Vec3* linear, uint32_t width, uint32_t height,
                                       float exposure_ev, int quality) {
    std::vector<uint8_t> rgb;
    try {
        rgb.resize(std::size_t(width) * height * 3);
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to encode the frame", "width");
    }
    tonemap_to_srgb8(linear, std::size_t(width) * height, exposure_ev, rgb.data());
    return encode_jpeg(rgb.data(), width, height, quality);
}

}  // namespace strata

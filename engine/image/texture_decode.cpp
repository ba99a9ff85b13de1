#include "engine/image/texture_decode.h"

#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include <png.h>
#include <turbojpeg.h>

namespace strata {

namespace {

constexpr const char* FIELD = "data";

/// 8-bit sRGB code to linear 16-bit, computed once.
const std::array<uint16_t, 256>& srgb_table() {
    static const std::array<uint16_t, 256> table = [] {
        std::array<uint16_t, 256> t{};
        for (int i = 0; i < 256; ++i) {
            const double c = i / 255.0;
            const double l = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
            t[i] = uint16_t(std::lround(l * 65535.0));
        }
        return t;
    }();
    return table;
}

uint32_t big_endian32(const uint8_t* p) {
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

/// PNG: the signature, then chunks (length, type, data, CRC) up to and including IEND.
std::size_t png_length(const uint8_t* p, std::size_t n) {
    std::size_t at = 8;
    while (at + 12 <= n) {
        const uint64_t length = big_endian32(p + at);
        const bool last = std::memcmp(p + at + 4, "IEND", 4) == 0;
        if (length > n - at - 12) return 0;
        at += 12 + std::size_t(length);
        if (last) return at;
    }
    return 0;
}

/// JPEG: SOI, then segments; after each start-of-scan, entropy-coded data in which 0xFF is
/// followed by 0x00 (a stuffed byte) or a restart marker, up to the next marker; EOI ends it.
std::size_t jpeg_length(const uint8_t* p, std::size_t n) {
    std::size_t at = 2;
    while (at + 1 < n) {
        if (p[at] != 0xFF) return 0;
        const uint8_t marker = p[at + 1];
        if (marker == 0xFF) {  // fill byte
            ++at;
            continue;
        }
        at += 2;
        if (marker == 0xD9) return at;                                    // EOI
        if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
        if (at + 2 > n) return 0;
        const std::size_t length = std::size_t(p[at]) << 8 | p[at + 1];
        if (length < 2 || length > n - at) return 0;
        at += length;
        if (marker != 0xDA) continue;
        while (at + 1 < n && !(p[at] == 0xFF && p[at + 1] != 0x00 &&
                               !(p[at + 1] >= 0xD0 && p[at + 1] <= 0xD7)))
            ++at;
    }
    return 0;
}

}  // namespace

Status check_texture_size(uint32_t width, uint32_t height, const TextureLimits& limits,
                          const char* format, bool alpha) {
    if (width == 0 || height == 0)
        return failure(ErrorCode::InvalidArgument,
                       std::string(format) + " image has no pixels (" + std::to_string(width) +
                           "x" + std::to_string(height) + ")",
                       FIELD);
    if (width > limits.max_side || height > limits.max_side)
        return failure(ErrorCode::TooLarge,
                       std::string(format) + " image is " + std::to_string(width) + "x" +
                           std::to_string(height) + ", over the largest side of " +
                           std::to_string(limits.max_side) + " texels",
                       FIELD);
    const uint64_t bytes =
        uint64_t(width) * height * (TEXTURE_BYTES_PER_TEXEL + (alpha ? TEXTURE_BYTES_PER_ALPHA : 0));
    if (bytes > limits.max_bytes)
        return failure(ErrorCode::TooLarge,
                       std::string(format) + " image is " + std::to_string(width) + "x" +
                           std::to_string(height) + " (" + std::to_string(bytes) +
                           " decoded bytes), over the " + std::to_string(limits.max_bytes) +
                           " bytes left in the texture budget (max_texture_mb)",
                       FIELD);
    return {};
}

namespace {

/// 8-bit codes to 16-bit values: sRGB decoded to linear, or data codes scaled as they are.
const std::array<uint16_t, 256>& code_table(TextureColorSpace space) {
    static const std::array<uint16_t, 256> linear = [] {
        std::array<uint16_t, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = uint16_t(i * 257);
        return t;
    }();
    return space == TextureColorSpace::Srgb ? srgb_table() : linear;
}

/// 8-bit pixels of `channels` (3: RGB, 4: RGBA) to the texels of `out` (sized here); the alpha
/// plane is kept only where some texel is not opaque.
void to_texels(const uint8_t* pixels, uint32_t channels, TextureColorSpace space,
               TextureImage& out) {
    const auto& table = code_table(space);
    const std::size_t n = std::size_t(out.width) * out.height;
    out.texels.resize(n * 3);
    bool opaque = true;
    for (std::size_t i = 0; i < n; ++i) {
        const uint8_t* p = pixels + i * channels;
        for (int c = 0; c < 3; ++c) out.texels[i * 3 + c] = table[p[c]];
        if (channels == 4) opaque = opaque && p[3] == 255;
    }
    if (opaque) return;
    out.alpha.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.alpha[i] = pixels[i * channels + 3];
}

// Step: PNG ------------------------------------------------------------------------------------

/// Everything the PNG decode owns, on the heap so a longjmp out of libpng skips no destructor.
struct PngState {
    const uint8_t* data = nullptr;
    std::size_t size = 0;
    std::size_t offset = 0;
    std::string error;
    std::vector<uint8_t> rgba;
    std::vector<png_bytep> rows;
    TextureImage image;
    png_structp png = nullptr;
    png_infop info = nullptr;

    ~PngState() { png_destroy_read_struct(&png, &info, nullptr); }
};

void png_read_bytes(png_structp png, png_bytep out, png_size_t length) {
    auto* s = static_cast<PngState*>(png_get_io_ptr(png));
    if (length > s->size - s->offset) png_error(png, "the file ends early (truncated)");
    std::memcpy(out, s->data + s->offset, length);
    s->offset += length;
}

[[noreturn]] void png_on_error(png_structp png, png_const_charp message) {
    auto* s = static_cast<PngState*>(png_get_error_ptr(png));
    if (s->error.empty()) s->error = message ? message : "unknown libpng error";
    png_longjmp(png, 1);
}

void png_on_warning(png_structp, png_const_charp) {}

Result<TextureImage> decode_png_texture(std::string_view bytes, const TextureLimits& limits,
                                        TextureColorSpace space) {
    auto s = std::make_unique<PngState>();
    s->data = reinterpret_cast<const uint8_t*>(bytes.data());
    s->size = bytes.size();
    s->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, s.get(), png_on_error, png_on_warning);
    s->info = s->png ? png_create_info_struct(s->png) : nullptr;
    if (!s->png || !s->info) return failure(ErrorCode::Internal, "libpng could not be initialised");
    Status size_ok;
    // libpng reports errors by longjmp back here; every object lives in `s`, made before.
    if (setjmp(png_jmpbuf(s->png)))
        return failure(ErrorCode::InvalidArgument, "corrupt PNG: " + s->error, FIELD);
    png_set_read_fn(s->png, s.get(), png_read_bytes);
    // The sides are checked below against our own limits, with our own message.
    png_set_user_limits(s->png, 0x7fffffff, 0x7fffffff);
    png_set_chunk_malloc_max(s->png, 8u << 20);
    png_read_info(s->png, s->info);
    // The budget counts an alpha plane for any image that may have one (it is dropped after the
    // decode when every texel is opaque).
    const bool may_have_alpha =
        (png_get_color_type(s->png, s->info) & PNG_COLOR_MASK_ALPHA) != 0 ||
        png_get_valid(s->png, s->info, PNG_INFO_tRNS) != 0;
    size_ok = check_texture_size(png_get_image_width(s->png, s->info),
                                 png_get_image_height(s->png, s->info), limits, "PNG",
                                 may_have_alpha);
    if (!size_ok) return Unexpected(size_ok.error());
    png_set_expand(s->png);
    png_set_strip_16(s->png);
    png_set_gray_to_rgb(s->png);
    png_set_add_alpha(s->png, 0xFF, PNG_FILLER_AFTER);
    png_set_interlace_handling(s->png);
    png_read_update_info(s->png, s->info);
    s->image.width = png_get_image_width(s->png, s->info);
    s->image.height = png_get_image_height(s->png, s->info);
    if (png_get_channels(s->png, s->info) != 4 ||
        png_get_rowbytes(s->png, s->info) != std::size_t(s->image.width) * 4)
        return failure(ErrorCode::InvalidArgument, "PNG pixel layout could not be read as RGBA",
                       FIELD);
    try {
        s->rgba.resize(std::size_t(s->image.width) * s->image.height * 4);
        s->rows.resize(s->image.height);
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to decode the PNG image", FIELD);
    }
    for (uint32_t y = 0; y < s->image.height; ++y)
        s->rows[y] = s->rgba.data() + std::size_t(y) * s->image.width * 4;
    png_read_image(s->png, s->rows.data());
    png_read_end(s->png, nullptr);
    try {
        to_texels(s->rgba.data(), 4, space, s->image);
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to decode the PNG image", FIELD);
    }
    return std::move(s->image);
}

// Step: JPEG -----------------------------------------------------------------------------------

struct TjHandle {
    tjhandle h = tjInitDecompress();
    ~TjHandle() {
        if (h) tjDestroy(h);
    }
};

Result<TextureImage> decode_jpeg_texture(std::string_view bytes, const TextureLimits& limits,
                                         TextureColorSpace space) {
    TjHandle tj;
    if (!tj.h) return failure(ErrorCode::Internal, "libturbojpeg could not be initialised");
    auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    if (bytes.size() > 0xFFFFFFFFu)
        return failure(ErrorCode::TooLarge, "JPEG file over 4 GiB", FIELD);
    const auto size = static_cast<unsigned long>(bytes.size());
    int width = 0, height = 0, subsampling = 0, colorspace = 0;
    if (tjDecompressHeader3(tj.h, data, size, &width, &height, &subsampling, &colorspace) != 0)
        return failure(ErrorCode::InvalidArgument,
                       std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.h), FIELD);
    if (width <= 0 || height <= 0)
        return failure(ErrorCode::InvalidArgument, "corrupt JPEG: the header gives no image size",
                       FIELD);
    if (Status s = check_texture_size(uint32_t(width), uint32_t(height), limits, "JPEG"); !s)
        return Unexpected(s.error());
    if (colorspace == TJCS_CMYK || colorspace == TJCS_YCCK)
        return failure(ErrorCode::InvalidArgument, "JPEG image is CMYK; only RGB and greyscale",
                       FIELD);
    TextureImage image;
    image.width = uint32_t(width);
    image.height = uint32_t(height);
    std::vector<uint8_t> rgb;
    try {
        rgb.resize(std::size_t(width) * height * 3);
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to decode the JPEG image", FIELD);
    }
    // Strict: a warning (truncated or damaged data) refuses the image; LIMITSCANS refuses
    // progressive files with absurd scan counts (a decode-time bomb).
    if (tjDecompress2(tj.h, data, size, rgb.data(), width, 0, height, TJPF_RGB,
                      TJFLAG_STOPONWARNING | TJFLAG_LIMITSCANS) != 0)
        return failure(ErrorCode::InvalidArgument,
                       std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.h), FIELD);
    try {
        to_texels(rgb.data(), 3, space, image);
    } catch (const std::bad_alloc&) {
        return failure(ErrorCode::TooLarge, "not enough memory to decode the JPEG image", FIELD);
    }
    return image;
}

}  // namespace

uint16_t srgb8_to_linear16(uint8_t code) {
    return srgb_table()[code];
}

std::size_t image_length(std::string_view bytes) {
    const auto* p = reinterpret_cast<const uint8_t*>(bytes.data());
    const char* format = texture_format(bytes);
    if (!format) return 0;
    return format[0] == 'p' ? png_length(p, bytes.size()) : jpeg_length(p, bytes.size());
}

const char* texture_format(std::string_view bytes) {
    static constexpr unsigned char PNG_SIGNATURE[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), PNG_SIGNATURE, 8) == 0) return "png";
    if (bytes.size() >= 3 && uint8_t(bytes[0]) == 0xFF && uint8_t(bytes[1]) == 0xD8 &&
        uint8_t(bytes[2]) == 0xFF)
        return "jpeg";
    return nullptr;
}

Result<TextureImage> decode_texture(std::string_view bytes, const TextureLimits& limits,
                                   TextureColorSpace space) {
    const char* format = texture_format(bytes);
    if (!format)
        return failure(ErrorCode::InvalidArgument,
                       bytes.empty() ? "the image is empty"
                                     : "the image is neither PNG nor JPEG (unknown signature)",
                       FIELD);
    return format[0] == 'p' ? decode_png_texture(bytes, limits, space)
                            : decode_jpeg_texture(bytes, limits, space);
}

}  // namespace strata

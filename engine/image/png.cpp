#include "engine/image/png.h"

#include <algorithm>
#include <cstring>

#include <png.h>
#include <zlib.h>

namespace strata {

namespace {

struct WriteState {
    std::string* out;
};

void write_bytes(png_structp png, png_bytep data, png_size_t length) {
    auto* state = static_cast<WriteState*>(png_get_io_ptr(png));
    state->out->append(reinterpret_cast<const char*>(data), length);
}

void flush_nothing(png_structp) {}

struct ReadState {
    const uint8_t* data;
    std::size_t size;
    std::size_t offset;
};

void read_bytes(png_structp png, png_bytep out, png_size_t length) {
    auto* state = static_cast<ReadState*>(png_get_io_ptr(png));
    if (state->offset + length > state->size) png_error(png, "truncated PNG");
    std::memcpy(out, state->data + state->offset, length);
    state->offset += length;
}

}  // namespace

Result<std::string> encode_png(const uint8_t* pixels, uint32_t width, uint32_t height, int channels,
                               int zlib_level) {
    if (channels != 3 && channels != 4)
        return failure(ErrorCode::InvalidArgument, "PNG needs 3 or 4 channels");
    if (width == 0 || height == 0)
        return failure(ErrorCode::InvalidArgument, "PNG needs a non-empty image");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        return failure(ErrorCode::Internal, "libpng could not be initialised");
    }
    std::string out;
    // Room for incompressible pixels, so the string never grows by copying.
    out.reserve(std::size_t(width) * height * channels + height + 65536);
    WriteState state{&out};
    // libpng reports errors by longjmp; nothing with a destructor lives between here and the end.
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return failure(ErrorCode::Internal, "libpng failed to encode the frame");
    }
    png_set_write_fn(png, &state, write_bytes, flush_nothing);
    png_set_IHDR(png, info, width, height, 8,
                 channels == 4 ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, std::clamp(zlib_level, 0, 9));
    // Run-length matching only: as small as level 1's full matcher on rendered frames (SUB
    // filtered), and a quarter faster. One large zlib buffer means few IDAT chunks.
    png_set_compression_strategy(png, Z_RLE);
    png_set_compression_buffer_size(png, 1 << 20);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    const std::size_t stride = std::size_t(width) * channels;
    for (uint32_t y = 0; y < height; ++y)
        png_write_row(png, const_cast<png_bytep>(pixels + y * stride));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return out;
}

Result<DecodedImage> decode_png(const uint8_t* data, std::size_t size) {
    if (size < 8 || png_sig_cmp(data, 0, 8) != 0)
        return failure(ErrorCode::InvalidArgument, "not a PNG file");
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_read_struct(&png, &info, nullptr);
        return failure(ErrorCode::Internal, "libpng could not be initialised");
    }
    ReadState state{data, size, 0};
    DecodedImage* image = new DecodedImage();  // owned below; survives a longjmp
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        delete image;
        return failure(ErrorCode::InvalidArgument, "corrupt PNG data");
    }
    png_set_read_fn(png, &state, read_bytes);
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_read_update_info(png, info);
    image->width = png_get_image_width(png, info);
    image->height = png_get_image_height(png, info);
    image->channels = png_get_channels(png, info);
    const std::size_t stride = png_get_rowbytes(png, info);
    image->pixels.resize(stride * image->height);
    for (uint32_t y = 0; y < image->height; ++y)
        png_read_row(png, image->pixels.data() + y * stride, nullptr);
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    DecodedImage result = std::move(*image);
    delete image;
    return result;
}

}  // namespace strata

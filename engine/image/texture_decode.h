#pragma once
// Decoding untrusted PNG and JPEG bytes into a TextureImage (libpng, libturbojpeg). The format
// comes from the first bytes, never from a name. The header is read first: an image larger than
// the limits is refused before any texel memory is allocated. Colour textures (TextureColorSpace::
// Srgb: what glTF and OBJ base-colour textures are) are converted to linear once, here; data
// textures (Linear: normal and roughness maps) keep their codes. Greyscale and palette images
// become RGB. A PNG's alpha (its alpha channel or tRNS chunk) is kept, unless it is opaque
// everywhere; JPEG has none.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "engine/core/result.h"
#include "engine/image/texture.h"

namespace strata {

/// Largest width or height accepted.
constexpr uint32_t MAX_TEXTURE_SIDE = 16384;

struct TextureLimits {
    uint32_t max_side = MAX_TEXTURE_SIDE;
    /// Decoded bytes (width * height * TEXTURE_BYTES_PER_TEXEL) the image may take.
    uint64_t max_bytes = uint64_t(1) << 30;
};

/// Which decoder the bytes call for: "png", "jpeg", or nullptr for neither.
const char* texture_format(std::string_view bytes);

/// The length of the PNG (through its IEND chunk) or JPEG (through its EOI marker) at the start
/// of `bytes`, found by walking its chunks or segments without decoding; 0 when it has no end
/// there (truncated, or neither format). Whatever follows is not part of the image.
std::size_t image_length(std::string_view bytes);

/// Checks a decoded image's size against `limits` (what decode_texture checks from the header),
/// for an image decoded earlier with wider limits. `format`: "PNG" or "JPEG"; `alpha`: the image
/// keeps an alpha plane (TEXTURE_BYTES_PER_ALPHA more per texel).
Status check_texture_size(uint32_t width, uint32_t height, const TextureLimits& limits,
                          const char* format, bool alpha = false);

/// An image decoded ahead of the rule that stores it (AddTexture::decoded), with the limits the
/// decode could know then: the rule checks what is left of the budget again.
struct DecodedTexture {
    Result<TextureImage> image;
};

/// Decodes a PNG or JPEG. Errors (field "data"): InvalidArgument for bytes that are neither or
/// are corrupt (the message says what the decoder found), TooLarge for an image over `limits`.
Result<TextureImage> decode_texture(std::string_view bytes, const TextureLimits& limits,
                                   TextureColorSpace space = TextureColorSpace::Srgb);

/// The linear value of an 8-bit sRGB code, as 0..65535.
uint16_t srgb8_to_linear16(uint8_t code);

}  // namespace strata

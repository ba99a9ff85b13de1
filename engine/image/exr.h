#pragma once
// OpenEXR encoding and decoding in memory (an Imf::OStream / Imf::IStream over a byte vector:
// never a temporary file). Scanline images, INCREASING_Y, any mix of HALF, FLOAT and UINT
// channels, compressed on OpenEXR's thread pool. Compressions (all lossless):
//   none  fastest, largest;
//   zip   ZIP_COMPRESSION (16 scanlines per block) at zlib level 1: the default for frames, the
//         smallest files on ids and float AOVs;
//   piz   wavelet + Huffman: fastest to compress half RGBA, about as small as zip there, larger
//         on float and id channels.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/result.h"

namespace strata {

enum class ExrCompression : uint8_t { None, Zip, Piz };

/// Channel type in the file.
enum class ExrPixel : uint8_t { Uint, Half, Float };

/// One channel to write. HALF and FLOAT channels read floats from `f32`, UINT channels read
/// `u32`; pixel (x, y) is element (y * width + x) * stride. Stride 0 repeats one value (HALF
/// channels only).
struct ExrChannel {
    std::string name;
    ExrPixel type = ExrPixel::Half;
    const float* f32 = nullptr;
    const uint32_t* u32 = nullptr;
    std::size_t stride = 1;
};

/// What the numbers of one UINT channel stand for: an entry of the file's ID manifest
/// (OpenEXR's `idManifest` attribute, ImfIDManifest.h) with one text component per id, not
/// hashed, valid for this frame only.
struct ExrIdTable {
    std::string channel;
    std::string component;  ///< what the texts are ("instance", "mesh")
    std::vector<std::pair<uint32_t, std::string>> entries;
};

/// Header attributes besides the channels.
struct ExrAttributes {
    /// OpenEXR's standard worldToCamera and worldToNDC (ImfStandardAttributes.h). glm matrices
    /// (column vectors) are written as they lie in memory, which is Imath's row-vector layout.
    std::optional<glm::mat4> world_to_camera;
    std::optional<glm::mat4> world_to_ndc;
    std::vector<ExrIdTable> ids;  ///< the ID manifest; none is written when empty
};

/// Encodes a width x height image with `channels` (OpenEXR sorts them by name in the file) and
/// `attributes`.
Result<std::string> encode_exr(uint32_t width, uint32_t height,
                               const std::vector<ExrChannel>& channels, ExrCompression compression,
                               const ExrAttributes& attributes = {});

/// One decoded channel: floats for HALF and FLOAT channels, integers for UINT ones.
struct DecodedExrChannel {
    std::string name;
    ExrPixel type = ExrPixel::Half;
    std::vector<float> f32;
    std::vector<uint32_t> u32;
};

/// A decoded scanline EXR (for tests and tools).
struct DecodedExr {
    uint32_t width = 0;
    uint32_t height = 0;
    std::optional<ExrCompression> compression;  ///< nullopt: some other compression
    std::vector<DecodedExrChannel> channels;    ///< in file order (sorted by name)
    std::vector<ExrIdTable> ids;                ///< the ID manifest's tables (first component)

    /// The channel called `name`, or nullptr.
    const DecodedExrChannel* find(const std::string& name) const;
};

/// Reads every channel of an in-memory scanline or tiled EXR with OpenEXR (an error for malformed
/// data).
Result<DecodedExr> decode_exr(const uint8_t* data, std::size_t size);
/// The same over encoded bytes held in a string (what encode_exr returns).
inline Result<DecodedExr> decode_exr(std::string_view bytes) {
    return decode_exr(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace strata

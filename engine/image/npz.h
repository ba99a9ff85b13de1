#pragma once
// NumPy's .npz in memory: a ZIP archive (entries stored, not compressed) of .npy arrays (format
// 1.0), which `numpy.load` reads with nothing else installed. Frames go out this way so that a
// client gets its image and AOVs as arrays without an EXR library (frame_encode.h).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"

namespace strata {

/// One array: C order, little-endian elements.
struct NpyArray {
    std::string name;                ///< the key numpy.load gives it (the entry is name + ".npy")
    std::string descr;               ///< numpy's dtype string: "<f4", "<u4", "<U12"
    std::vector<std::size_t> shape;  ///< product * element size == bytes.size()
    std::string_view bytes;          ///< the elements, borrowed until encode_npz returns
};

/// The .npy file of `a`: magic, version 1.0, the header dict padded to 64 bytes, the elements.
std::string npy_header(const NpyArray& a);

/// An .npz archive of `arrays` (names unique). A TooLarge error when the archive would pass the
/// 4 GiB a ZIP without its 64-bit extension can address.
Result<std::string> encode_npz(const std::vector<NpyArray>& arrays);

/// Texts as numpy's fixed-width unicode ("<U{n}", UTF-32 code points, n the longest text in code
/// points, at least 1): fills `out` and returns the dtype. Invalid UTF-8 becomes U+FFFD.
std::string utf32_array(const std::vector<std::string>& texts, std::vector<uint32_t>& out);

}  // namespace strata

#pragma once
// CRC-32C (Castagnoli, the polynomial of iSCSI, ext4 metadata and LevelDB's log records), table
// driven, eight bytes per step ("slicing by 8"). Journal records and snapshots carry one each.

#include <cstddef>
#include <cstdint>

namespace strata::durable {

/// Extends `crc` (0 to start) over `size` bytes. crc32c("123456789") == 0xE3069283.
uint32_t crc32c(const void* data, std::size_t size, uint32_t crc = 0);

}  // namespace strata::durable

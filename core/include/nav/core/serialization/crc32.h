#pragma once
// CRC-32 (IEEE 802.3 / zlib / PNG: reflected polynomial 0xEDB88320, initial value and final XOR
// 0xFFFFFFFF), table driven. Check value: crc32("123456789") == 0xCBF43926. Used by the map
// section container (sections.h) and the daemon's checkpoint files.

#include <cstddef>
#include <cstdint>
#include <span>

namespace nav::core {

/// Continues a CRC: crc32(a + b) == crc32_update(crc32(a), b); crc32_update(0, x) == crc32(x).
std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::uint8_t> data);
inline std::uint32_t crc32(std::span<const std::uint8_t> data) { return crc32_update(0, data); }

}  // namespace nav::core

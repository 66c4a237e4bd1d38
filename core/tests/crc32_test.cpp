// CRC-32 (IEEE 802.3, reflected, init and final xor 0xFFFFFFFF) of the checkpoint files and
// sections against known vectors (the standard check value, zlib.crc32), and the incremental
// form against the whole.
#include "nav/core/serialization/crc32.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace nav::core {
namespace {

std::span<const std::uint8_t> bytes_of(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

TEST(Crc32, KnownVectors) {
  EXPECT_EQ(crc32(bytes_of("")), 0x00000000u);
  EXPECT_EQ(crc32(bytes_of("a")), 0xE8B7BE43u);
  EXPECT_EQ(crc32(bytes_of("123456789")), 0xCBF43926u);  // the CRC-32 check value
  EXPECT_EQ(crc32(bytes_of("The quick brown fox jumps over the lazy dog")), 0x414FA339u);
  const std::vector<std::uint8_t> zeros(32, 0);
  EXPECT_EQ(crc32(zeros), 0x190A55ADu);  // zlib.crc32(bytes(32))
}

TEST(Crc32, IncrementalEqualsWhole) {
  std::vector<std::uint8_t> data(1000);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(3 + 31 * i);
  const std::span<const std::uint8_t> all(data);
  for (std::size_t split : {0u, 1u, 17u, 999u, 1000u}) {
    EXPECT_EQ(crc32_update(crc32(all.first(split)), all.subspan(split)), crc32(all)) << split;
  }
}

}  // namespace
}  // namespace nav::core

// Checkpoint file format: header encode / verify. Layout in nav/daemon/checkpoint.h.
#include <algorithm>
#include <cstring>
#include <iterator>

#include "nav/daemon/checkpoint/checkpoint.h"
#include "nav/core/serialization/crc32.h"

namespace nav::daemon {
namespace {

constexpr char kMagic[8] = {'N', 'A', 'V', 'D', 'C', 'K', 'P', 'T'};

void put_le(std::vector<std::uint8_t>& out, std::size_t offset, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out[offset + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

std::uint64_t get_le(std::span<const std::uint8_t> bytes, std::size_t offset, int n) {
  std::uint64_t value = 0;
  for (int i = 0; i < n; ++i) value |= std::uint64_t{bytes[offset + i]} << (8 * i);
  return value;
}

std::optional<Checkpoint> reject(std::string* reason, std::string text) {
  if (reason) *reason = std::move(text);
  return std::nullopt;
}

}  // namespace

std::vector<std::uint8_t> encode_checkpoint(std::uint32_t payload_version, std::uint64_t sequence,
                                            std::span<const std::uint8_t> payload) {
  // Sized once and filled by index (GCC 12 -O3 misreports inserts after reserve()).
  std::vector<std::uint8_t> out(kCheckpointHeaderBytes + payload.size(), 0);
  std::copy(std::begin(kMagic), std::end(kMagic), out.begin());
  put_le(out, 8, kCheckpointFormatVersion, 4);
  put_le(out, 12, payload_version, 4);
  put_le(out, 16, sequence, 8);
  put_le(out, 24, payload.size(), 8);
  put_le(out, 32, core::crc32(payload), 4);
  put_le(out, 36, core::crc32(std::span(out).first(36)), 4);
  std::copy(payload.begin(), payload.end(), out.begin() + kCheckpointHeaderBytes);
  return out;
}

std::optional<Checkpoint> decode_checkpoint(std::span<const std::uint8_t> bytes,
                                            std::string* reason) {
  if (bytes.size() < kCheckpointHeaderBytes) {
    return reject(reason, "truncated header: " + std::to_string(bytes.size()) + " of " +
                              std::to_string(kCheckpointHeaderBytes) + " bytes");
  }
  if (std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return reject(reason, "not a navd checkpoint (bad magic)");
  }
  const auto header_crc = static_cast<std::uint32_t>(get_le(bytes, 36, 4));
  if (core::crc32(bytes.first(36)) != header_crc) return reject(reason, "header CRC-32 mismatch");
  const auto format = static_cast<std::uint32_t>(get_le(bytes, 8, 4));
  if (format != kCheckpointFormatVersion) {
    return reject(reason, "unsupported format version " + std::to_string(format));
  }
  const std::uint64_t length = get_le(bytes, 24, 8);
  const std::uint64_t expected = kCheckpointHeaderBytes + length;
  if (bytes.size() < expected) {
    return reject(reason, "truncated: " + std::to_string(bytes.size()) + " of " +
                              std::to_string(expected) + " bytes");
  }
  if (bytes.size() > expected) {
    return reject(reason, std::to_string(bytes.size() - expected) + " trailing bytes after " +
                              std::to_string(expected));
  }
  const std::span<const std::uint8_t> payload = bytes.subspan(kCheckpointHeaderBytes);
  if (core::crc32(payload) != static_cast<std::uint32_t>(get_le(bytes, 32, 4))) {
    return reject(reason, "payload CRC-32 mismatch");
  }
  Checkpoint checkpoint;
  checkpoint.payload_version = static_cast<std::uint32_t>(get_le(bytes, 12, 4));
  checkpoint.sequence = get_le(bytes, 16, 8);
  checkpoint.payload.assign(payload.begin(), payload.end());
  return checkpoint;
}

}  // namespace nav::daemon

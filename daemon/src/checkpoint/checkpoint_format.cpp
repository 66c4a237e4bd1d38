// Checkpoint file format: header encode / verify. Layout in nav/daemon/checkpoint/checkpoint.h.
#include <algorithm>
#include <array>
#include <iterator>

#include "nav/core/serialization/archive.h"
#include "nav/core/serialization/crc32.h"
#include "nav/daemon/checkpoint/checkpoint.h"

namespace nav::daemon {
namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {'N', 'A', 'V', 'D', 'C', 'K', 'P', 'T'};
constexpr std::size_t kHeaderCrcOffset = 36;  // the header CRC covers the bytes before it

/// The 40-byte file header (the layout in checkpoint.h), written and read by one function.
struct Header {
  std::array<std::uint8_t, 8> magic{};
  std::uint32_t format_version = 0;
  std::uint32_t payload_version = 0;
  std::uint64_t sequence = 0;
  std::uint64_t payload_length = 0;
  std::uint32_t payload_crc = 0;
  std::uint32_t header_crc = 0;
};

template <class Archive>
void serialize(Archive& ar, Header& h) {
  ar(h.magic, "magic");
  ar(h.format_version, "format version");
  ar(h.payload_version, "payload version");
  ar(h.sequence, "sequence");
  ar(h.payload_length, "payload length");
  ar(h.payload_crc, "payload CRC-32");
  ar(h.header_crc, "header CRC-32");
}

std::optional<Checkpoint> reject(std::string* reason, std::string text) {
  if (reason) *reason = std::move(text);
  return std::nullopt;
}

}  // namespace

std::vector<std::uint8_t> encode_checkpoint(std::uint32_t payload_version, std::uint64_t sequence,
                                            std::span<const std::uint8_t> payload) {
  Header h;
  h.magic = kMagic;
  h.format_version = kCheckpointFormatVersion;
  h.payload_version = payload_version;
  h.sequence = sequence;
  h.payload_length = payload.size();
  h.payload_crc = core::crc32(payload);
  const std::vector<std::uint8_t> unsigned_header = core::to_bytes(h);
  h.header_crc = core::crc32(std::span(unsigned_header).first(kHeaderCrcOffset));
  const std::vector<std::uint8_t> header = core::to_bytes(h);
  // Sized once and filled by index (GCC 12 -O3 misreports inserts after reserve()).
  std::vector<std::uint8_t> out(kCheckpointHeaderBytes + payload.size(), 0);
  std::copy(header.begin(), header.end(), out.begin());
  std::copy(payload.begin(), payload.end(), out.begin() + kCheckpointHeaderBytes);
  return out;
}

std::optional<Checkpoint> decode_checkpoint(std::span<const std::uint8_t> bytes,
                                            std::string* reason) {
  if (bytes.size() < kCheckpointHeaderBytes) {
    return reject(reason, "truncated header: " + std::to_string(bytes.size()) + " of " +
                              std::to_string(kCheckpointHeaderBytes) + " bytes");
  }
  Header h;
  core::ReadArchive ar(bytes.first(kCheckpointHeaderBytes), "checkpoint header");
  ar(h, "header");
  if (!ar.finish().ok()) return reject(reason, ar.finish().message());
  if (h.magic != kMagic) return reject(reason, "not a navd checkpoint (bad magic)");
  if (core::crc32(bytes.first(kHeaderCrcOffset)) != h.header_crc) {
    return reject(reason, "header CRC-32 mismatch");
  }
  if (h.format_version != kCheckpointFormatVersion) {
    return reject(reason, "unsupported format version " + std::to_string(h.format_version));
  }
  const std::uint64_t expected = kCheckpointHeaderBytes + h.payload_length;
  if (bytes.size() < expected) {
    return reject(reason, "truncated: " + std::to_string(bytes.size()) + " of " +
                              std::to_string(expected) + " bytes");
  }
  if (bytes.size() > expected) {
    return reject(reason, std::to_string(bytes.size() - expected) + " trailing bytes after " +
                              std::to_string(expected));
  }
  const std::span<const std::uint8_t> payload = bytes.subspan(kCheckpointHeaderBytes);
  if (core::crc32(payload) != h.payload_crc) return reject(reason, "payload CRC-32 mismatch");
  Checkpoint checkpoint;
  checkpoint.payload_version = h.payload_version;
  checkpoint.sequence = h.sequence;
  checkpoint.payload.assign(payload.begin(), payload.end());
  return checkpoint;
}

}  // namespace nav::daemon

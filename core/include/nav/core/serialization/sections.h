#pragma once
// A small section container for map checkpoints: a versioned list of (tag, version, bytes)
// sections, each with its own CRC-32, so that the core map (ESDF, bounds; map_codec.h) and the
// daemon's own state (last applied measurement time, frame-id -> state map, link history,
// counters) travel in one payload and each part evolves its schema independently.
//
// Layout, little-endian:
//   offset 0   magic "NAVSECTS" (8 bytes)
//          8   u32 container version (kSectionContainerVersion)
//         12   u32 number of sections N
//         16   N x { u32 tag, u32 section version, u64 length, u32 CRC-32, bytes }
//              (the CRC covers the tag, version and length fields and the bytes, so a flipped
//              tag of an optional section is caught as well)
// Nothing may follow the last section. Tags are four ASCII characters read as a little-endian
// u32 (section_tag("ESDF")), unique within a container.
//
// Decoding checks magic, version, every length against the bytes present (before allocating),
// duplicate tags, trailing bytes and, unless switched off, every section's CRC; each error says
// what and at which offset. No file I/O here (the daemon's checkpoint store writes the bytes).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "nav/core/status.h"

namespace nav::core {

inline constexpr std::uint32_t kSectionContainerVersion = 1;
inline constexpr std::size_t kSectionContainerHeaderBytes = 16;
inline constexpr std::size_t kSectionHeaderBytes = 20;

/// The tag of four ASCII characters, e.g. section_tag("ESDF").
constexpr std::uint32_t section_tag(const char (&name)[5]) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(name[0])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(name[3])) << 24;
}
/// "ESDF" for printable tags, else "0x..." (for error messages).
std::string section_tag_name(std::uint32_t tag);

class SectionWriter {
 public:
  /// Appends a section; kInvalidArgument if the tag is already present.
  Status add(std::uint32_t tag, std::uint32_t version, std::span<const std::uint8_t> bytes);
  /// The container bytes (header + sections in the order added).
  std::vector<std::uint8_t> finish() const;

 private:
  struct Entry {
    std::uint32_t tag;
    std::uint32_t version;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Entry> sections_;
};

/// One decoded section: a view into the decoded buffer (valid while that buffer lives).
struct SectionView {
  std::uint32_t tag = 0;
  std::uint32_t version = 0;
  std::size_t offset = 0;  ///< where the section's bytes start in the container
  std::span<const std::uint8_t> bytes;
};

struct SectionDecodeOptions {
  /// Check each section's CRC-32. Off only to test that decoding alone refuses inconsistent
  /// sizes (corruption tests) or when an outer checksum already covered the bytes.
  bool verify_crc = true;
};

class SectionSet {
 public:
  /// Parses a container; on error *out is left unchanged.
  static Status decode(std::span<const std::uint8_t> bytes, SectionSet* out,
                       SectionDecodeOptions options = {});

  const std::vector<SectionView>& sections() const { return sections_; }
  /// The section with `tag`, nullptr if absent.
  const SectionView* find(std::uint32_t tag) const;
  /// The section with `tag` and version `version`: kInvalidArgument naming the tag when it is
  /// missing or of another version.
  Status require(std::uint32_t tag, std::uint32_t version, const SectionView** out) const;

 private:
  std::vector<SectionView> sections_;
};

}  // namespace nav::core

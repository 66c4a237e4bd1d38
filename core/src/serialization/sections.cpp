// Section container for map checkpoints (see nav/core/serialization/sections.h).
#include "nav/core/serialization/sections.h"

#include <array>
#include <cstdio>
#include <utility>

#include "nav/core/serialization/archive.h"
#include "nav/core/serialization/crc32.h"

namespace nav::core {
namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {'N', 'A', 'V', 'S', 'E', 'C', 'T', 'S'};

/// The container's header and each section's header (layouts in sections.h), both ways.
struct ContainerHeader {
  std::array<std::uint8_t, 8> magic{};
  std::uint32_t version = 0;
  std::uint32_t count = 0;
};
struct SectionHeader {
  std::uint32_t tag = 0, version = 0;
  std::uint64_t length = 0;
  std::uint32_t crc = 0;  ///< of the header's first 16 bytes and the section's bytes
};

template <class Archive>
void serialize(Archive& ar, ContainerHeader& h) {
  ar(h.magic, "magic");
  ar(h.version, "container version");
  ar(h.count, "section count");
}

template <class Archive>
void serialize(Archive& ar, SectionHeader& h) {
  ar(h.tag, "section tag");
  ar(h.version, "section version");
  ar(h.length, "section length");
  ar(h.crc, "section CRC-32");
}

/// CRC-32 of a section: its header without the CRC field, then its bytes.
std::uint32_t section_crc(std::span<const std::uint8_t> header16,
                          std::span<const std::uint8_t> bytes) {
  return crc32_update(crc32(header16), bytes);
}

Status bad(const std::string& message, std::size_t offset) {
  return Status::Error(StatusCode::kInvalidArgument, "map section container: " + message +
                                                         " at offset " + std::to_string(offset));
}

}  // namespace

std::string section_tag_name(std::uint32_t tag) {
  std::string name;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((tag >> (8 * i)) & 0xFFu);
    if (c < 0x20 || c > 0x7E) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "0x%08X", tag);
      return hex;
    }
    name.push_back(c);
  }
  return name;
}

Status SectionWriter::add(std::uint32_t tag, std::uint32_t version,
                          std::span<const std::uint8_t> bytes) {
  for (const Entry& e : sections_) {
    if (e.tag == tag) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "SectionWriter::add: section " + section_tag_name(tag) + " added twice");
    }
  }
  sections_.push_back(Entry{tag, version, std::vector<std::uint8_t>(bytes.begin(), bytes.end())});
  return Status::Ok();
}

std::vector<std::uint8_t> SectionWriter::finish() const {
  WriteArchive ar;
  ContainerHeader container{kMagic, kSectionContainerVersion,
                            static_cast<std::uint32_t>(sections_.size())};
  ar(container, "container");
  for (const Entry& e : sections_) {
    SectionHeader h{e.tag, e.version, e.bytes.size(), 0};
    const std::vector<std::uint8_t> header = to_bytes(h);
    h.crc = section_crc(std::span(header).first(16), e.bytes);
    ar(h, "section header");
    std::span<const std::uint8_t> bytes(e.bytes);
    ar.raw(bytes, bytes.size(), "section bytes");
  }
  return ar.take();
}

Status SectionSet::decode(std::span<const std::uint8_t> bytes, SectionSet* out,
                          SectionDecodeOptions options) {
  ReadArchive ar(bytes, "map section container");
  ContainerHeader container;
  ar(container.magic, "magic");
  if (!ar.ok()) return ar.status();
  if (container.magic != kMagic) return bad("bad magic (not NAVSECTS)", 0);
  ar(container.version, "container version");
  if (!ar.ok()) return ar.status();
  if (container.version != kSectionContainerVersion) {
    return bad("unsupported container version " + std::to_string(container.version), 8);
  }
  ar(container.count, "section count");
  if (!ar.check_count(container.count, kSectionHeaderBytes, "section count")) return ar.status();
  SectionSet set;
  set.sections_.reserve(container.count);
  for (std::uint32_t i = 0; i < container.count; ++i) {
    const std::size_t header_at = ar.offset();
    SectionHeader h;
    ar(h, "section header");
    if (!ar.ok()) return ar.status();
    SectionView v;
    v.tag = h.tag;
    v.version = h.version;
    if (h.length > ar.remaining()) {
      return bad("section " + std::to_string(i) + " (" + section_tag_name(v.tag) + ") length " +
                     std::to_string(h.length) + " exceeds the " +
                     std::to_string(ar.remaining()) + " bytes left",
                 header_at);
    }
    if (set.find(v.tag) != nullptr) {
      return bad("duplicate section " + section_tag_name(v.tag), header_at);
    }
    v.offset = ar.offset();
    ar.raw(v.bytes, static_cast<std::size_t>(h.length), "section bytes");
    if (!ar.ok()) return ar.status();
    if (options.verify_crc && section_crc(bytes.subspan(header_at, 16), v.bytes) != h.crc) {
      return bad("CRC-32 mismatch in section " + section_tag_name(v.tag), header_at);
    }
    set.sections_.push_back(v);
  }
  if (Status s = ar.finish(); !s.ok()) return s;
  *out = std::move(set);
  return Status::Ok();
}

const SectionView* SectionSet::find(std::uint32_t tag) const {
  for (const SectionView& v : sections_) {
    if (v.tag == tag) return &v;
  }
  return nullptr;
}

Status SectionSet::require(std::uint32_t tag, std::uint32_t version,
                           const SectionView** out) const {
  const SectionView* v = find(tag);
  if (v == nullptr) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "map section container: no " + section_tag_name(tag) + " section");
  }
  if (v->version != version) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "map section container: section " + section_tag_name(tag) +
                             " has version " + std::to_string(v->version) + ", this build reads " +
                             std::to_string(version) + " (at offset " + std::to_string(v->offset) +
                             ")");
  }
  *out = v;
  return Status::Ok();
}

}  // namespace nav::core

// Section container for map checkpoints (see nav/core/serialization/sections.h).
#include "nav/core/serialization/sections.h"

#include <cstdio>
#include <cstring>
#include <utility>

#include "nav/core/serialization/byte_io.h"
#include "nav/core/serialization/crc32.h"

namespace nav::core {
namespace {

constexpr char kMagic[8] = {'N', 'A', 'V', 'S', 'E', 'C', 'T', 'S'};

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
  ByteWriter w;
  w.bytes(std::span(reinterpret_cast<const std::uint8_t*>(kMagic), sizeof kMagic));
  w.u32(kSectionContainerVersion);
  w.u32(static_cast<std::uint32_t>(sections_.size()));
  for (const Entry& e : sections_) {
    const std::size_t header_at = w.data().size();
    w.u32(e.tag);
    w.u32(e.version);
    w.u64(e.bytes.size());
    const std::uint32_t crc =
        crc32_update(crc32(std::span(w.data()).subspan(header_at, 16)), e.bytes);
    w.u32(crc);
    w.bytes(e.bytes);
  }
  return w.take();
}

Status SectionSet::decode(std::span<const std::uint8_t> bytes, SectionSet* out,
                          SectionDecodeOptions options) {
  ByteReader r(bytes, "map section container");
  std::span<const std::uint8_t> magic;
  if (Status s = r.raw(&magic, sizeof kMagic, "magic"); !s.ok()) return s;
  if (std::memcmp(magic.data(), kMagic, sizeof kMagic) != 0) {
    return bad("bad magic (not NAVSECTS)", 0);
  }
  std::uint32_t version = 0, count = 0;
  if (Status s = r.u32(&version, "container version"); !s.ok()) return s;
  if (version != kSectionContainerVersion) {
    return bad("unsupported container version " + std::to_string(version), 8);
  }
  if (Status s = r.u32(&count, "section count"); !s.ok()) return s;
  if (Status s = r.check_count(count, kSectionHeaderBytes, "section count"); !s.ok()) return s;
  SectionSet set;
  set.sections_.reserve(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::size_t header_at = r.offset();
    SectionView v;
    std::uint64_t length = 0;
    std::uint32_t crc = 0;
    if (Status s = r.u32(&v.tag, "section tag"); !s.ok()) return s;
    if (Status s = r.u32(&v.version, "section version"); !s.ok()) return s;
    if (Status s = r.u64(&length, "section length"); !s.ok()) return s;
    if (Status s = r.u32(&crc, "section CRC-32"); !s.ok()) return s;
    if (length > r.remaining()) {
      return bad("section " + std::to_string(i) + " (" + section_tag_name(v.tag) + ") length " +
                     std::to_string(length) + " exceeds the " + std::to_string(r.remaining()) +
                     " bytes left",
                 header_at);
    }
    if (set.find(v.tag) != nullptr) {
      return bad("duplicate section " + section_tag_name(v.tag), header_at);
    }
    v.offset = r.offset();
    if (Status s = r.raw(&v.bytes, static_cast<std::size_t>(length), "section bytes"); !s.ok()) {
      return s;
    }
    if (options.verify_crc && crc32_update(crc32(bytes.subspan(header_at, 16)), v.bytes) != crc) {
      return bad("CRC-32 mismatch in section " + section_tag_name(v.tag), header_at);
    }
    set.sections_.push_back(v);
  }
  if (Status s = r.expect_end(); !s.ok()) return s;
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

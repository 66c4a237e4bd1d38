// Streaming PD0 decoder: framing, checksum, resynchronisation and byte accounting.
// Framing per "WorkHorse Commands and Output Data Format", PD0 "Header Data Format": 0x7F 0x7F,
// byte count N (excluding the 2 checksum bytes), spare, number of data types, offsets;
// checksum "Reserved for RDI use / Checksum Data Format": sum of the N bytes modulo 65536.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "nav/drivers/codecs/pd0.h"
#include "pd0_wire.h"

namespace nav::drivers {

using namespace pd0_wire;

namespace {

/// True for the data type IDs of the WorkHorse manual's PD0 table: fixed and variable leader,
/// velocity, correlation, echo intensity, percent good, status and bottom track.
bool documented_type(uint16_t id) {
  switch (id) {
    case kFixedLeaderId:
    case kVariableLeaderId:
    case 0x0100:
    case 0x0200:
    case 0x0300:
    case 0x0400:
    case 0x0500:
    case kBottomTrackId:
      return true;
    default:
      return false;
  }
}

}  // namespace

bool Pd0DecoderOptions::validate() const { return max_ensemble_bytes >= 64; }

Pd0Decoder::Pd0Decoder(Pd0DecoderOptions options) : options_(options) {
  if (!options_.validate()) {
    throw std::invalid_argument("Pd0DecoderOptions: max_ensemble_bytes must be >= 64, got " +
                                std::to_string(options_.max_ensemble_bytes));
  }
  buffer_.reserve(std::min<std::size_t>(options_.max_ensemble_bytes, 1 << 14));
}

void Pd0Decoder::drop(std::size_t n) {
  start_ += n;
  stats_.dropped_bytes += n;
}

void Pd0Decoder::compact() {
  if (start_ == 0) return;
  buffer_.erase(buffer_.begin(), buffer_.begin() + std::ptrdiff_t(start_));
  start_ = 0;
}

Pd0Decoder::Step Pd0Decoder::try_decode(const HostTime& received, std::vector<Pd0Ensemble>& out) {
  const uint8_t* p = buffer_.data() + start_;
  std::size_t avail = buffer_.size() - start_;
  // Search for the header IDs 0x7F 0x7F (a lone trailing 0x7F may be the first half).
  std::size_t i = 0;
  while (i < avail && !(p[i] == kHeaderId && (i + 1 == avail || p[i + 1] == kHeaderId))) ++i;
  if (i > 0) {
    drop(i);
    p += i;
    avail -= i;
  }
  if (avail < kHeaderFixedBytes) return Step::kNeedMore;

  const std::size_t n = le16(p + 2);
  const std::size_t types = p[5];  // one byte: every count up to kMaxDataTypes is valid
  const std::size_t table_end = kHeaderFixedBytes + 2 * types;
  if (types == 0 || n < table_end + 2 || n + kChecksumBytes > options_.max_ensemble_bytes) {
    ++stats_.malformed;
    return Step::kDropOne;
  }
  // Reject false headers (0x7F7F in garbage or inside data) before waiting for N bytes: RDI
  // instruments write the fixed leader first, right after the offset table, and the other
  // types in increasing offset order.
  if (avail < table_end + 2) return Step::kNeedMore;
  std::size_t previous = 0;
  for (std::size_t k = 0; k < types; ++k) {
    const std::size_t offset = le16(p + kHeaderFixedBytes + 2 * k);
    if ((k == 0 && offset != table_end) || offset <= previous || offset + 2 > n) {
      ++stats_.malformed;
      return Step::kDropOne;
    }
    previous = offset;
  }
  if (le16(p + table_end) != kFixedLeaderId) {
    ++stats_.malformed;
    return Step::kDropOne;
  }
  const std::size_t total = n + kChecksumBytes;
  if (avail < total) return Step::kNeedMore;

  if (pd0_checksum({p, n}) != le16(p + n)) {
    ++stats_.checksum_failures;
    return Step::kDropOne;
  }
  out.emplace_back();
  int rejected = 0;
  switch (parse_pd0_ensemble({p, total}, out.back(), rejected)) {
    case Pd0ParseError::kMalformed:
      out.pop_back();
      ++stats_.malformed;
      return Step::kDropOne;
    case Pd0ParseError::kUnsupported:
      out.pop_back();
      ++stats_.unsupported;
      drop(total);
      return Step::kEmitted;
    case Pd0ParseError::kOutOfRange:
      ++stats_.out_of_range;
      break;
    case Pd0ParseError::kNone:
      break;
  }
  out.back().time.host = received;
  for (uint16_t id : out.back().skipped_type_ids) {
    ++skipped_types_.total;
    if (!documented_type(id)) ++skipped_types_.unknown;
  }
  ++stats_.records;
  start_ += total;
  return Step::kEmitted;
}

void Pd0Decoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                      std::vector<Pd0Ensemble>& out) {
  stats_.bytes += bytes.size();
  while (!bytes.empty()) {
    // Never hold more than one maximal ensemble: after decoding stops for want of bytes, the
    // buffer holds less than the ensemble it waits for, so there is always room for a byte.
    compact();
    if (buffer_.size() >= options_.max_ensemble_bytes) {  // unreachable; never spin
      ++stats_.malformed;
      drop(1);
      compact();
    }
    const std::size_t room = options_.max_ensemble_bytes - buffer_.size();
    const std::size_t take = std::min(room, bytes.size());
    buffer_.insert(buffer_.end(), bytes.begin(), bytes.begin() + std::ptrdiff_t(take));
    bytes = bytes.subspan(take);
    for (;;) {
      const Step step = try_decode(received, out);
      if (step == Step::kNeedMore) break;
      if (step == Step::kDropOne) drop(1);
    }
  }
}

}  // namespace nav::drivers

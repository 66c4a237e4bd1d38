// libFuzzer target for the altimeter codecs: the protocol comes from the first byte; whole vs
// three-chunk decoding must agree, the counters must add up, a range is present exactly for
// valid readings, and readings of ordinary size round-trip through the encoder.
#include <cmath>
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/altimeter.h"

namespace {

using namespace nav::drivers;

void check(bool condition) {
  if (!condition) std::abort();
}

std::vector<AltimeterRecord> decode(std::span<const uint8_t> data, std::size_t a, std::size_t b,
                                    const AltimeterFormat& format, DecodeStats& stats) {
  AltimeterDecoder decoder(format);
  std::vector<AltimeterRecord> out;
  decoder.feed(data.subspan(0, a), {}, out);
  decoder.feed(data.subspan(a, b - a), {}, out);
  decoder.feed(data.subspan(b), {}, out);
  stats = decoder.stats();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  AltimeterFormat format;
  format.protocol = static_cast<AltimeterProtocol>(bytes[0] % 4);
  format.require_checksum = (bytes[1] & 1) == 0;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const std::size_t a = data.empty() ? 0 : bytes[0] % (data.size() + 1);
  const std::size_t b = a + (data.size() - a == 0 ? 0 : bytes[1] % (data.size() - a + 1));
  DecodeStats whole_stats, chunked_stats;
  const auto whole = decode(data, 0, 0, format, whole_stats);
  const auto chunked = decode(data, a, b, format, chunked_stats);
  check(whole_stats.to_json() == chunked_stats.to_json());
  check(whole.size() == chunked.size() && whole_stats.records == whole.size());
  check(whole_stats.bytes == data.size() && whole_stats.dropped_bytes <= data.size());
  for (const auto& record : whole) {
    check(record.range_m.has_value() == (record.status == AltimeterStatus::kValid));
    check(std::isfinite(record.raw_value_m));
    if (record.range_m) {
      check(*record.range_m >= format.min_range_m && *record.range_m <= format.max_range_m);
    }
    if (std::abs(record.raw_value_m) > 1.0e6) continue;
    const std::string text = encode_altimeter(record, format);
    AltimeterDecoder again(format);
    std::vector<AltimeterRecord> out;
    again.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, {}, out);
    check(out.size() == 1 && again.stats().dropped_bytes == 0);
  }
  return 0;
}

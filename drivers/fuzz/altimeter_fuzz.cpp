// libFuzzer target for the altimeter codecs: the protocol comes from the first byte; whole vs
// three-chunk decoding must agree, the counters must add up, a range is present exactly for
// valid readings, and readings of ordinary size round-trip through the encoder.
#include <cmath>
#include <span>
#include <vector>

#include "fuzz_support.h"
#include "nav/drivers/codecs/altimeter.h"

using namespace nav::drivers;
using nav::drivers::fuzz::as_bytes;
using nav::drivers::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  AltimeterFormat format;
  format.protocol = static_cast<AltimeterProtocol>(bytes[0] % 4);
  format.require_checksum = (bytes[1] & 1) == 0;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const auto runs = fuzz::decode_whole_and_chunked<AltimeterDecoder, AltimeterRecord>(
      bytes[0], bytes[1], data, format);
  for (const auto& record : runs.whole.records) {
    check(record.range_m.has_value() == (record.status == AltimeterStatus::kValid));
    check(std::isfinite(record.raw_value_m));
    if (record.range_m) {
      check(*record.range_m >= format.min_range_m && *record.range_m <= format.max_range_m);
    }
    if (std::abs(record.raw_value_m) > 1.0e6) continue;
    const std::string text = encode_altimeter(record, format);
    AltimeterDecoder again(format);
    std::vector<AltimeterRecord> out;
    again.feed(as_bytes(text), {}, out);
    check(out.size() == 1 && again.stats().dropped_bytes == 0);
  }
  return 0;
}

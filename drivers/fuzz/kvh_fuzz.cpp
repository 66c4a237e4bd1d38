// libFuzzer target for the KVH DSP-3000 codec: whole vs three-chunk decoding must agree, the
// counters must add up, and every record away from the range limits must round-trip through
// the encoder. The mode comes from the first byte.
#include <cmath>
#include <span>
#include <vector>

#include "fuzz_support.h"
#include "nav/drivers/codecs/kvh.h"

using namespace nav::drivers;
using nav::drivers::fuzz::as_bytes;
using nav::drivers::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  KvhOptions options;
  options.mode = static_cast<KvhOutputMode>(bytes[0] % 3);
  options.unit = (bytes[1] & 1) ? KvhAngleUnit::kRadians : KvhAngleUnit::kDegrees;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const auto runs =
      fuzz::decode_whole_and_chunked<KvhDecoder, KvhRecord>(bytes[0], bytes[1], data, options);
  for (const auto& record : runs.whole.records) {
    const auto& value = options.mode == KvhOutputMode::kRate ? record.rate_radps : record.angle_rad;
    check(value.has_value() == record.sensor_valid);
    if (value) check(std::isfinite(*value));
    const double limit = options.mode == KvhOutputMode::kIntegratedAngle
                             ? options.max_integrated_angle_rad
                             : options.max_rate_radps;
    if (value && std::abs(*value) > 0.999 * limit) continue;  // encoder rounding at the edge
    const std::string text = encode_kvh(record, options);
    if (text.size() > options.max_line_chars + 2) continue;
    KvhDecoder again(options);
    std::vector<KvhRecord> out;
    again.feed(as_bytes(text), {}, out);
    check(out.size() == 1 && out[0].sensor_valid == record.sensor_valid);
  }
  return 0;
}

// libFuzzer target for the KVH DSP-3000 codec: whole vs three-chunk decoding must agree, the
// counters must add up, and every record away from the range limits must round-trip through
// the encoder. The mode comes from the first byte.
#include <cmath>
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/kvh.h"

namespace {

using namespace nav::drivers;

void check(bool condition) {
  if (!condition) std::abort();
}

std::vector<KvhRecord> decode(std::span<const uint8_t> data, std::size_t a, std::size_t b,
                              const KvhOptions& options, DecodeStats& stats) {
  KvhDecoder decoder(options);
  std::vector<KvhRecord> out;
  decoder.feed(data.subspan(0, a), {}, out);
  decoder.feed(data.subspan(a, b - a), {}, out);
  decoder.feed(data.subspan(b), {}, out);
  stats = decoder.stats();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  KvhOptions options;
  options.mode = static_cast<KvhOutputMode>(bytes[0] % 3);
  options.unit = (bytes[1] & 1) ? KvhAngleUnit::kRadians : KvhAngleUnit::kDegrees;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const std::size_t a = data.empty() ? 0 : bytes[0] % (data.size() + 1);
  const std::size_t b = a + (data.size() - a == 0 ? 0 : bytes[1] % (data.size() - a + 1));
  DecodeStats whole_stats, chunked_stats;
  const auto whole = decode(data, 0, 0, options, whole_stats);
  const auto chunked = decode(data, a, b, options, chunked_stats);
  check(whole_stats.to_json() == chunked_stats.to_json());
  check(whole.size() == chunked.size() && whole_stats.records == whole.size());
  check(whole_stats.bytes == data.size() && whole_stats.dropped_bytes <= data.size());
  for (const auto& record : whole) {
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
    again.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, {}, out);
    check(out.size() == 1 && out[0].sensor_valid == record.sensor_valid);
  }
  return 0;
}

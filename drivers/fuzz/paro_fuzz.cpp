// libFuzzer target for the Paroscientific codec: whole vs three-chunk decoding must agree, the
// counters must add up, and replies away from the range limits must round-trip through the
// poll-reply encoder. The pressure unit comes from the first byte.
#include <cmath>
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/paroscientific.h"

namespace {

using namespace nav::drivers;

void check(bool condition) {
  if (!condition) std::abort();
}

std::vector<ParoRecord> decode(std::span<const uint8_t> data, std::size_t a, std::size_t b,
                               const ParoOptions& options, DecodeStats& stats) {
  ParoDecoder decoder(options);
  std::vector<ParoRecord> out;
  decoder.feed(data.subspan(0, a), {}, out);
  decoder.feed(data.subspan(a, b - a), {}, out);
  decoder.feed(data.subspan(b), {}, out);
  stats = decoder.stats();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  ParoOptions options;
  options.unit = static_cast<ParoPressureUnit>(bytes[0] % 10);  // all but kCustom
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
    check(std::isfinite(record.pressure_pa));
    check(record.pressure_pa >= options.min_pressure_pa);
    check(record.pressure_pa <= options.max_pressure_pa);
    if (record.pressure_pa < options.min_pressure_pa + 1.0 ||
        record.pressure_pa > options.max_pressure_pa - 1.0) {
      continue;  // encoder rounding at the edge of the range
    }
    const std::string text = encode_paro_reply(record, options, 6);
    ParoDecoder again(options);
    std::vector<ParoRecord> out;
    again.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, {}, out);
    check(out.size() == 1 && out[0].source_id == record.source_id);
  }
  return 0;
}

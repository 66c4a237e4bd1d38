// libFuzzer target for the Paroscientific codec: whole vs three-chunk decoding must agree, the
// counters must add up, and replies away from the range limits must round-trip through the
// poll-reply encoder. The pressure unit comes from the first byte.
#include <cmath>
#include <span>
#include <vector>

#include "fuzz_support.h"
#include "nav/drivers/codecs/paroscientific.h"

using namespace nav::drivers;
using nav::drivers::fuzz::as_bytes;
using nav::drivers::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  ParoOptions options;
  options.unit = static_cast<ParoPressureUnit>(bytes[0] % 10);  // all but kCustom
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const auto runs =
      fuzz::decode_whole_and_chunked<ParoDecoder, ParoRecord>(bytes[0], bytes[1], data, options);
  for (const auto& record : runs.whole.records) {
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
    again.feed(as_bytes(text), {}, out);
    check(out.size() == 1 && out[0].source_id == record.source_id);
  }
  return 0;
}

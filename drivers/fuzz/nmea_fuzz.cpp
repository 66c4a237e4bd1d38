// libFuzzer target for the NMEA heading/attitude codec: the input is fed whole and again in
// three chunks (split points from the first two bytes); both runs must agree exactly, the
// counters must add up, and every decoded record must encode to a sentence that decodes again.
#include <span>
#include <vector>

#include "fuzz_support.h"
#include "nav/drivers/codecs/nmea.h"

using nav::drivers::NmeaDecoder;
using nav::drivers::NmeaOptions;
using nav::drivers::NmeaRecord;
using nav::drivers::fuzz::as_bytes;
using nav::drivers::fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  NmeaOptions options;
  options.require_checksum = (bytes[0] & 1) == 0;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const auto runs = nav::drivers::fuzz::decode_whole_and_chunked<NmeaDecoder, NmeaRecord>(
      bytes[0], bytes[1], data, options);
  const auto& whole = runs.whole.records;
  const auto& chunked = runs.chunked.records;
  for (std::size_t i = 0; i < whole.size(); ++i) {
    const std::string text = nav::drivers::encode_nmea(whole[i], options);
    check(text == nav::drivers::encode_nmea(chunked[i], options));
    NmeaDecoder again(options);
    std::vector<NmeaRecord> out;
    again.feed(as_bytes(text), {}, out);
    check(out.size() == 1 && again.stats().dropped_bytes == 0);
  }
  return 0;
}

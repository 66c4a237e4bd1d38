// libFuzzer target for the NMEA heading/attitude codec: the input is fed whole and again in
// three chunks (split points from the first two bytes); both runs must agree exactly, the
// counters must add up, and every decoded record must encode to a sentence that decodes again.
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/nmea.h"

namespace {

using nav::drivers::NmeaDecoder;
using nav::drivers::NmeaOptions;
using nav::drivers::NmeaRecord;

void check(bool condition) {
  if (!condition) std::abort();
}

std::vector<NmeaRecord> decode_chunked(std::span<const uint8_t> data, std::size_t a, std::size_t b,
                                       const NmeaOptions& options,
                                       nav::drivers::DecodeStats& stats) {
  NmeaDecoder decoder(options);
  std::vector<NmeaRecord> out;
  decoder.feed(data.subspan(0, a), {}, out);
  decoder.feed(data.subspan(a, b - a), {}, out);
  decoder.feed(data.subspan(b), {}, out);
  stats = decoder.stats();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  if (size < 2) return 0;
  NmeaOptions options;
  options.require_checksum = (bytes[0] & 1) == 0;
  const std::span<const uint8_t> data(bytes + 2, size - 2);
  const std::size_t a = data.empty() ? 0 : bytes[0] % (data.size() + 1);
  const std::size_t b = a + (data.size() - a == 0 ? 0 : bytes[1] % (data.size() - a + 1));

  nav::drivers::DecodeStats whole_stats, chunked_stats;
  const auto whole = decode_chunked(data, 0, 0, options, whole_stats);
  const auto chunked = decode_chunked(data, a, b, options, chunked_stats);
  check(whole_stats.to_json() == chunked_stats.to_json());
  check(whole.size() == chunked.size());
  check(whole_stats.records == whole.size());
  check(whole_stats.bytes == data.size());
  check(whole_stats.dropped_bytes <= whole_stats.bytes);
  for (std::size_t i = 0; i < whole.size(); ++i) {
    const std::string text = nav::drivers::encode_nmea(whole[i], options);
    check(text == nav::drivers::encode_nmea(chunked[i], options));
    NmeaDecoder again(options);
    std::vector<NmeaRecord> out;
    again.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, {}, out);
    check(out.size() == 1 && again.stats().dropped_bytes == 0);
  }
  return 0;
}

// libFuzzer target for the PD6 codec: whole vs three-chunk feeding give the same lines and
// counters, the buffer stays bounded, and every decoded line survives encode -> decode ->
// encode unchanged.
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/codecs/pd6.h"

using nav::drivers::HostTime;
using nav::drivers::Pd6Decoder;
using nav::drivers::Pd6Record;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> input(data, size);
  const HostTime host{1, 2};

  Pd6Decoder whole;
  std::vector<Pd6Record> reference;
  whole.feed(input, host, reference);

  Pd6Decoder chunked;
  std::vector<Pd6Record> out;
  const std::size_t a = size > 0 ? data[0] % (size + 1) : 0;
  const std::size_t b = size > 1 ? a + (data[1] * 7u) % (size - a + 1) : a;
  chunked.feed(input.subspan(0, a), host, out);
  chunked.feed(input.subspan(a, b - a), host, out);
  chunked.feed(input.subspan(b), host, out);
  check(chunked.buffered_bytes() <= Pd6Decoder::kMaxLineBytes);

  const auto& s = whole.stats();
  check(s.bytes == size);
  check(s.records == reference.size());
  check(s.dropped_bytes + whole.buffered_bytes() <= size);
  check(s.to_json() == chunked.stats().to_json());
  check(out.size() == reference.size());

  for (std::size_t i = 0; i < reference.size(); ++i) {
    const std::string encoded = nav::drivers::encode_pd6(reference[i]);
    check(nav::drivers::encode_pd6(out[i]) == encoded);
    check(out[i].time.sensor_time_us == reference[i].time.sensor_time_us);
    Pd6Decoder again;
    std::vector<Pd6Record> decoded;
    again.feed({reinterpret_cast<const uint8_t*>(encoded.data()), encoded.size()}, host, decoded);
    check(decoded.size() == 1);
    check(nav::drivers::encode_pd6(decoded[0]) == encoded);
  }
  return 0;
}

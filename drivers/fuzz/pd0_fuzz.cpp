// libFuzzer target for the PD0 codec. The input is fed whole and in three chunks (split points
// taken from its first bytes); both must give the same ensembles and counters. Invariants:
// every byte accounted for, bounded buffer, at most 255 data types per ensemble, the same
// skipped-type counts, and every decoded ensemble survives encode -> decode -> encode byte for
// byte, also with its skipped data types re-encoded (empty bodies) in their order.
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/pd0.h"

using nav::drivers::DecodeStats;
using nav::drivers::HostTime;
using nav::drivers::Pd0Decoder;
using nav::drivers::Pd0DecoderOptions;
using nav::drivers::Pd0Ensemble;
using nav::drivers::Pd0RawDataType;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

bool same_stats(const DecodeStats& a, const DecodeStats& b) {
  return a.records == b.records && a.bytes == b.bytes && a.dropped_bytes == b.dropped_bytes &&
         a.checksum_failures == b.checksum_failures && a.malformed == b.malformed &&
         a.out_of_range == b.out_of_range && a.unsupported == b.unsupported;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> input(data, size);
  Pd0DecoderOptions options;
  options.max_ensemble_bytes = 4096;  // also exercise the bound with fuzzer-sized inputs
  const HostTime host{1, 2};

  Pd0Decoder whole(options);
  std::vector<Pd0Ensemble> reference;
  whole.feed(input, host, reference);

  Pd0Decoder chunked(options);
  std::vector<Pd0Ensemble> out;
  const std::size_t a = size > 0 ? data[0] % (size + 1) : 0;
  const std::size_t b = size > 1 ? a + (data[1] * 7u) % (size - a + 1) : a;
  chunked.feed(input.subspan(0, a), host, out);
  check(chunked.buffered_bytes() <= options.max_ensemble_bytes);
  chunked.feed(input.subspan(a, b - a), host, out);
  check(chunked.buffered_bytes() <= options.max_ensemble_bytes);
  chunked.feed(input.subspan(b), host, out);

  const DecodeStats& s = whole.stats();
  check(s.bytes == size);
  check(s.records == reference.size());
  check(s.dropped_bytes + whole.buffered_bytes() <= size);
  check(same_stats(s, chunked.stats()));
  check(chunked.buffered_bytes() == whole.buffered_bytes());
  check(out.size() == reference.size());
  check(chunked.skipped_types().total == whole.skipped_types().total);
  check(chunked.skipped_types().unknown == whole.skipped_types().unknown);
  check(whole.skipped_types().unknown <= whole.skipped_types().total);
  uint64_t skipped = 0;

  for (std::size_t i = 0; i < reference.size(); ++i) {
    const std::vector<uint8_t> encoded = nav::drivers::encode_pd0(reference[i]);
    check(nav::drivers::encode_pd0(out[i]) == encoded);  // split gave the same values
    Pd0Decoder again;
    std::vector<Pd0Ensemble> decoded;
    again.feed(encoded, host, decoded);
    check(decoded.size() == 1);
    check(again.stats().dropped_bytes == 0 && again.buffered_bytes() == 0);
    check(nav::drivers::encode_pd0(decoded[0]) == encoded);

    const std::vector<uint16_t>& ids = reference[i].skipped_type_ids;
    check(ids == out[i].skipped_type_ids);
    check(ids.size() + (reference[i].bottom_track ? 3 : 2) <= 255);
    skipped += ids.size();
    std::vector<Pd0RawDataType> extra;
    for (uint16_t id : ids) extra.push_back({id, {}});
    Pd0Decoder with_types;
    std::vector<Pd0Ensemble> decoded_with_types;
    with_types.feed(nav::drivers::encode_pd0(reference[i], extra), host, decoded_with_types);
    check(decoded_with_types.size() == 1);
    check(decoded_with_types[0].skipped_type_ids == ids);
    check(nav::drivers::encode_pd0(decoded_with_types[0]) == encoded);
  }
  check(skipped == whole.skipped_types().total);
  return 0;
}

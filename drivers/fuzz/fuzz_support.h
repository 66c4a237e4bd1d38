#pragma once
// Shared harness of the ASCII codec fuzz targets (altimeter, KVH, NMEA, Paroscientific): the
// input after its first two bytes is decoded whole and again in three chunks whose split points
// come from those two bytes; both runs must agree and the counters must add up. Included by
// relative path from the *_fuzz.cpp beside it (not a fuzz target itself).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <string_view>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"

namespace nav::drivers::fuzz {

/// Aborts (a finding for libFuzzer) when `condition` is false.
inline void check(bool condition) {
  if (!condition) std::abort();
}

/// The bytes of `text`, as a decoder's feed() takes them.
inline std::span<const uint8_t> as_bytes(std::string_view text) {
  return {reinterpret_cast<const uint8_t*>(text.data()), text.size()};
}

/// Records and counters of one decoding run.
template <typename Record>
struct DecodeRun {
  std::vector<Record> records;
  DecodeStats stats;
};

/// Feeds `data` to a fresh `Decoder(options)` as the chunks [0, a), [a, b), [b, end)
/// (0 <= a <= b <= data.size()), all with a default HostTime.
template <typename Decoder, typename Record, typename Options>
DecodeRun<Record> decode_in_chunks(std::span<const uint8_t> data, std::size_t a, std::size_t b,
                                   const Options& options) {
  Decoder decoder(options);
  DecodeRun<Record> run;
  decoder.feed(data.subspan(0, a), {}, run.records);
  decoder.feed(data.subspan(a, b - a), {}, run.records);
  decoder.feed(data.subspan(b), {}, run.records);
  run.stats = decoder.stats();
  return run;
}

/// Both runs over the same data: fed whole, and fed in three chunks.
template <typename Record>
struct WholeAndChunked {
  DecodeRun<Record> whole;
  DecodeRun<Record> chunked;
};

/// Decodes `data` (the fuzz input without its first two bytes `first`, `second`) whole and in
/// three chunks split where `first` and `second` say, and checks that both runs give the same
/// counters and record count, that every record is counted and that every input byte is counted
/// with no more dropped than were read.
template <typename Decoder, typename Record, typename Options>
WholeAndChunked<Record> decode_whole_and_chunked(uint8_t first, uint8_t second,
                                                 std::span<const uint8_t> data,
                                                 const Options& options) {
  const std::size_t a = data.empty() ? 0 : first % (data.size() + 1);
  const std::size_t b = a + (data.size() - a == 0 ? 0 : second % (data.size() - a + 1));
  WholeAndChunked<Record> runs{decode_in_chunks<Decoder, Record>(data, 0, 0, options),
                               decode_in_chunks<Decoder, Record>(data, a, b, options)};
  const DecodeStats& stats = runs.whole.stats;
  check(stats.to_json() == runs.chunked.stats.to_json());
  check(runs.whole.records.size() == runs.chunked.records.size());
  check(stats.records == runs.whole.records.size());
  check(stats.bytes == data.size() && stats.dropped_bytes <= data.size());
  return runs;
}

}  // namespace nav::drivers::fuzz

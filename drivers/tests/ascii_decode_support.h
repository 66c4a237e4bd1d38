#pragma once
// Test helper of the ASCII codec tests (altimeter, KVH, NMEA, Paroscientific): decode a text in
// one piece with a fresh decoder and keep its records and counters. Included by relative path
// from the *_test.cpp beside it; test-only.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers::test {

/// Records and counters of one decoding run.
template <typename Record>
struct DecodeResult {
  std::vector<Record> records;
  DecodeStats stats;
};

/// Feeds all of `text` at once to a fresh `Decoder(options)`, received at `host`.
template <typename Decoder, typename Record, typename Options>
DecodeResult<Record> decode_text(const std::string& text, const Options& options,
                                 const HostTime& host) {
  Decoder decoder(options);
  DecodeResult<Record> result;
  decoder.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, host, result.records);
  result.stats = decoder.stats();
  return result;
}

}  // namespace nav::drivers::test

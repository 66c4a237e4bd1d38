#pragma once
// Formats known to `navtool parse`. Each format decodes a byte stream with the drivers' codecs
// and writes one JSON object per decoded record (one line each) to `records`, accumulating the
// decoder's counters in `stats`. A format registers itself from the file that implements it
// (parse_formats_<group>.cpp) with a file-scope `const ParseFormatRegistration`.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::tool {

struct ParseOptions {
  std::string can_config_path;  ///< --can-config: CAN signal definitions (format "can" only)
};

struct ParseFormat {
  std::string help;  ///< one line for --help
  std::function<void(std::istream& in, std::ostream& records, nav::drivers::DecodeStats& stats,
                     const ParseOptions& options)>
      run;
};

/// Every registered format by its --format name.
std::map<std::string, ParseFormat>& parse_format_registry();

struct ParseFormatRegistration {
  ParseFormatRegistration(const std::string& name, ParseFormat format) {
    parse_format_registry().emplace(name, std::move(format));
  }
};

/// Reads `in` to its end in chunks of at most `chunk_bytes` and hands every chunk to
/// `feed(std::span<const uint8_t>)`.
template <typename Feed>
void read_chunks(std::istream& in, Feed&& feed, std::size_t chunk_bytes = 4096) {
  std::vector<uint8_t> chunk(chunk_bytes);
  while (in) {
    in.read(reinterpret_cast<char*>(chunk.data()), std::streamsize(chunk.size()));
    const auto got = std::size_t(in.gcount());
    if (got == 0) break;
    feed(std::span<const uint8_t>(chunk.data(), got));
  }
}

/// Feeds `in` chunk by chunk to `decoder.feed(bytes, HostTime{}, std::vector<Record>&)` and calls
/// `on_record(record)` for every record in the order decoded. The decoder's counters and any
/// bytes it still buffers at the end are left to the caller.
template <typename Record, typename Decoder, typename OnRecord>
void decode_stream(std::istream& in, Decoder& decoder, OnRecord&& on_record) {
  std::vector<Record> out;
  read_chunks(in, [&](std::span<const uint8_t> bytes) {
    out.clear();
    decoder.feed(bytes, drivers::HostTime{}, out);
    for (const auto& record : out) on_record(record);
  });
}

}  // namespace nav::tool

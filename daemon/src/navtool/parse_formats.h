#pragma once
// Formats known to `navtool parse`. Each format decodes a byte stream with the drivers' codecs
// and writes one JSON object per decoded record (one line each) to `records`, accumulating the
// decoder's counters in `stats`. A format registers itself from the file that implements it
// (parse_formats_<group>.cpp) with a file-scope `const ParseFormatRegistration`.

#include <functional>
#include <iosfwd>
#include <map>
#include <string>

#include "nav/drivers/codecs/decode_stats.h"

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

}  // namespace nav::tool

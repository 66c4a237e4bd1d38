#pragma once
// Formats known to `navtool parse`. Each format decodes a byte stream with the drivers' codecs
// and writes one JSON object per decoded record (one line each) to `records`, accumulating the
// decoder's counters in `stats`. Formats are grouped by the file that implements them.

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"

namespace nav::tool {

struct ParseOptions {
  std::string can_config_path;  ///< --can-config: CAN signal definitions (format "can" only)
};

struct ParseFormat {
  std::string name;  ///< value of --format
  std::string help;  ///< one line for --help
  std::function<void(std::istream& in, std::ostream& records, nav::drivers::DecodeStats& stats,
                     const ParseOptions& options)>
      run;
};

std::vector<ParseFormat> dvl_parse_formats();    ///< pd0, pd6 (parse_formats_dvl.cpp)
std::vector<ParseFormat> ascii_parse_formats();  ///< nmea, kvh, paro, altimeter, can (parse_formats_ascii.cpp)

}  // namespace nav::tool

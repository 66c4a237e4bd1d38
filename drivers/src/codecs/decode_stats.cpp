#include "nav/drivers/codecs/decode_stats.h"

#include <sstream>

namespace nav::drivers {

DecodeStats& DecodeStats::operator+=(const DecodeStats& o) {
  records += o.records;
  bytes += o.bytes;
  dropped_bytes += o.dropped_bytes;
  checksum_failures += o.checksum_failures;
  malformed += o.malformed;
  out_of_range += o.out_of_range;
  unsupported += o.unsupported;
  return *this;
}

std::string DecodeStats::to_json() const {
  std::ostringstream out;
  out << "{\"records\":" << records << ",\"bytes\":" << bytes
      << ",\"dropped_bytes\":" << dropped_bytes << ",\"checksum_failures\":" << checksum_failures
      << ",\"malformed\":" << malformed << ",\"out_of_range\":" << out_of_range
      << ",\"unsupported\":" << unsupported << "}";
  return out.str();
}

}  // namespace nav::drivers

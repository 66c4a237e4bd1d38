#pragma once
// Counters every streaming decoder keeps: what it decoded and what it dropped and why.
// Published in navd's health message and printed by `navtool parse` as its summary.

#include <cstdint>
#include <string>

namespace nav::drivers {

struct DecodeStats {
  uint64_t records = 0;            ///< records decoded and emitted
  uint64_t bytes = 0;              ///< bytes fed to the decoder
  uint64_t dropped_bytes = 0;      ///< bytes discarded while resynchronising or in bad records
  uint64_t checksum_failures = 0;  ///< records whose checksum did not match
  uint64_t malformed = 0;          ///< framing/length/field errors (not checksum)
  uint64_t out_of_range = 0;       ///< records rejected by range checks on decoded values
  uint64_t unsupported = 0;        ///< well-formed records of a type the decoder does not use

  DecodeStats& operator+=(const DecodeStats& o);
  /// One-line JSON object, e.g. {"records":3,"bytes":120,...}.
  std::string to_json() const;
};

}  // namespace nav::drivers

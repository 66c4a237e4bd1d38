#pragma once
// Streaming decoder of candump text logs (linux-can/can-utils candump.c, lib.c), classic CAN:
//  * log file format (`candump -l`, and `-L` on stdout):  `(1699999999.123456) can0 123#DEADBEEF`
//    identifiers of 3 hex digits are standard, of 8 extended; `123#R` (or `123#R4`) is a
//    remote request; data bytes may be separated by '.', an optional `_<hex>` len8_dlc suffix
//    is accepted. CAN FD (`123##1...`), CAN XL and error frames (CAN_ERR_FLAG in the 8-digit
//    identifier) are counted as unsupported.
//  * ASCII screen format: `  can0  123   [4]  DE AD BE EF`, optionally preceded by a time
//    stamp `(1699999999.123456)` (-t a), `(000.000123)` (-t d/z, relative) or
//    `(2023-11-14 22:13:19.123456)` (-t A, taken as UTC); `[4]  remote request` for RTR.
//    CAN FD lengths are printed with two digits (`[08]`) and counted as unsupported.
// A frame's time is the log's time stamp (the host/kernel receive time of the original
// capture) in both HostTime fields, since a log has only one clock; lines without a time stamp
// take the `received` time given to feed(). Lines are at most kMaxLineBytes; longer ones are
// dropped and counted as malformed.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

struct CanLogFrame {
  uint32_t id = 0;  ///< 11- or 29-bit identifier, no flag bits
  bool extended = false;
  bool remote = false;
  uint8_t dlc = 0;  ///< data length 0..8 (for remote frames the requested length)
  std::array<uint8_t, 8> data{};
  HostTime time;                          ///< see the file comment
  std::array<char, 16> interface_name{};  ///< e.g. "can0", NUL-terminated (truncated to 15)
  uint32_t line_bytes = 0;  ///< bytes of the log line incl. its newline (set by the decoder)

  std::span<const uint8_t> payload() const { return {data.data(), remote ? 0u : dlc}; }
};

/// Result of parsing one line.
enum class CandumpLineResult { kFrame, kBlank, kUnsupported, kMalformed };

/// Parses one line (without its newline). `frame.time` is set only when the line has a time
/// stamp (the caller keeps its default otherwise).
CandumpLineResult parse_candump_line(std::string_view line, CanLogFrame& frame, bool& has_time);

/// Formats a frame as a candump log line (`(sec.usec) iface ID#DATA`), the inverse of the
/// parser for the log format; used by tests and the simulator.
std::string format_candump_log_line(const CanLogFrame& frame);

class CandumpLogDecoder {
 public:
  static constexpr size_t kMaxLineBytes = 512;

  /// Decodes every complete line in `bytes` (lines may be split across calls).
  void feed(std::span<const uint8_t> bytes, const HostTime& received,
            std::vector<CanLogFrame>& out);
  /// Decodes a last line that had no newline.
  void finish(const HostTime& received, std::vector<CanLogFrame>& out);
  const DecodeStats& stats() const { return stats_; }

 private:
  void end_line(const HostTime& received, std::vector<CanLogFrame>& out);

  std::string line_;
  bool overlong_ = false;  ///< the current line exceeded kMaxLineBytes: drop until newline
  size_t overlong_bytes_ = 0;
  DecodeStats stats_;
};

}  // namespace nav::drivers

#pragma once
// Teledyne RDI PD6 ("WorkHorse Commands and Output Data Format", "Special Output Data
// Formats", PD6 Output Format): ASCII lines, CR LF terminated, one group per ensemble in the
// order :SA, :TS, :WI, :BI, :WS, :BS, :WE, :BE, :WD, :BD. A streaming decoder that emits one
// record PER LINE (not grouped: a group may be cut by the instrument's output settings), and
// an encoder.
//
//   :SA,±PP.PP,±RR.RR,HHH.HH                       pitch, roll, heading (deg)
//   :TS,YYMMDDHHmmsshh,SS.S,±TT.T,DDDD.D,CCCC.C,BBB time, salinity (ppt), temperature (degC),
//                                                  depth of transducer (m), sound speed (m/s),
//                                                  built-in-test result (hex)
//   :WI/:BI,±XXXXX,±YYYYY,±ZZZZZ,±EEEEE,S          instrument-referenced velocity (mm/s) X Y Z
//                                                  error, status A (good) / V (bad)
//   :WS/:BS,±TTTTT,±LLLLL,±NNNNN,S                 ship-referenced: transverse, longitudinal,
//                                                  normal (mm/s), status
//   :WE/:BE,±EEEEE,±NNNNN,±UUUUU,S                 earth-referenced: east, north, up (mm/s)
//   :WD/:BD,±EEEEEEEE.EE,±NNNNNNNN.NN,±UUUUUUUU.UU,DDDD.DD,TTT.TT
//                                                  distance made good east, north, up (m),
//                                                  range to bottom / water-mass centre (m),
//                                                  time since the last good velocity (s)
// W = water-mass reference layer, B = bottom track. Unlike PD0's bottom track, PD6 velocities
// are of the vehicle over the bottom (the manual: PD4/5/6/13 "assume that the bottom is
// stationary and that the DVL or vessel is moving"). -32768 marks an invalid velocity.
//
// Conventions: SI units and radians. A velocity line with status V, a -32768 component or a
// value outside its range gives empty optionals for its velocities (range rejections are
// counted in stats().out_of_range). Sensor time: a :TS line carries its own time; the lines
// after it up to the next :SA (the start of the next ensemble) carry the same time; :SA and
// lines before any :TS carry none.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

/// :SA system attitude.
struct Pd6Attitude {
  std::optional<double> pitch_rad;    ///< [-pi/2, pi/2]
  std::optional<double> roll_rad;     ///< [-pi/2, pi/2]
  std::optional<double> heading_rad;  ///< [0, 2pi)
};

/// :TS timing and scaling (its time is the record's sensor_time_us).
struct Pd6TimingScaling {
  std::optional<double> salinity_ppt;
  std::optional<double> temperature_c;
  std::optional<double> depth_m;  ///< depth of transducer
  std::optional<double> sound_speed_mps;
  uint16_t bit_result = 0;  ///< built-in test result, 0 = all passed
};

enum class Pd6Reference : uint8_t { kWaterMass, kBottom };
enum class Pd6Frame : uint8_t { kInstrument, kShip, kEarth };

/// :WI :BI :WS :BS :WE :BE velocities. Components: instrument X, Y, Z, error; ship
/// transverse, longitudinal, normal (4th empty); earth east, north, up (4th empty).
struct Pd6Velocity {
  Pd6Reference reference = Pd6Reference::kBottom;
  Pd6Frame frame = Pd6Frame::kEarth;
  std::array<std::optional<double>, 4> velocity_mps{};
  bool valid = false;  ///< status flag A
};

/// :WD :BD distance made good since the first ensemble.
struct Pd6Distance {
  Pd6Reference reference = Pd6Reference::kBottom;
  std::array<std::optional<double>, 3> distance_enu_m{};
  std::optional<double> range_m;             ///< range to bottom / water-mass layer centre
  std::optional<double> time_since_valid_s;  ///< time since the last good velocity
};

struct Pd6Record {
  Timestamps time;
  std::variant<Pd6Attitude, Pd6TimingScaling, Pd6Velocity, Pd6Distance> value;
};

/// The line's two-letter ID: "SA", "TS", "WI", "BI", "WS", "BS", "WE", "BE", "WD" or "BD".
std::string pd6_line_name(const Pd6Record& record);

/// Streaming PD6 decoder. A line starts at ':' and ends at LF (a CR before it is removed);
/// bytes outside lines, over-long lines (> kMaxLineBytes), malformed lines and lines of other
/// IDs are dropped and counted (malformed / unsupported). Every byte fed ends up in an emitted
/// line, in stats().dropped_bytes or (one partial line) in buffered_bytes(). out_of_range
/// counts emitted lines with at least one value rejected by its range check.
class Pd6Decoder {
 public:
  static constexpr std::size_t kMaxLineBytes = 128;

  void feed(std::span<const uint8_t> bytes, const HostTime& received, std::vector<Pd6Record>& out);
  const DecodeStats& stats() const { return stats_; }
  std::size_t buffered_bytes() const { return line_.size(); }

 private:
  void end_line(const HostTime& received, std::vector<Pd6Record>& out);
  void drop_line();

  std::string line_;                         ///< current line from ':' (empty while searching)
  bool discarding_ = false;                  ///< inside an over-long line: drop up to its LF
  std::optional<int64_t> ensemble_time_us_;  ///< last :TS time of the current ensemble
  DecodeStats stats_;
};

/// Decodes one line without its CR LF (e.g. ":SA, +1.20, -0.50,123.45"). Returns empty for
/// a malformed line; `unsupported` is set for a well-formed line of another ID;
/// `out_of_range_fields` counts rejected values.
std::optional<Pd6Record> parse_pd6_line(std::string_view line, bool& unsupported,
                                        int& out_of_range_fields);

/// Encodes one record as a line ending in CR LF, in the manual's field widths. Empty values
/// are written -32768 (velocities, with status V) or as an out-of-range value.
std::string encode_pd6(const Pd6Record& record);

}  // namespace nav::drivers

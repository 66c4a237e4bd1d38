#pragma once
// NMEA 0183 heading and attitude decoder/encoder: true heading `$--HDT` (any talker), iXblue
// `$PHTRO` pitch/roll and the iXblue "standard" proprietary sentences `$PIXSE,...`
// (ATITUD, HEADNG, POSITI, SPEED_, STDHRP, STDPOS, STDSPD, STATUS, ALGSTS). Other well-formed
// sentences are counted as unsupported.
//
// Framing (NMEA 0183 v4.10 section 5.3): `$<address>,<fields>*hh<CR><LF>`, hh = XOR of the
// characters between '$' and '*', at most 82 characters including '$' and CR LF. Proprietary
// sentences (address starting with 'P') may use a longer, configurable limit.
//
// Conventions of the decoded values (core/README.md): angles in radians, wrapped to (-pi, pi];
// Euler angles of the body FRD frame in the local-level NED frame, roll positive starboard
// down, pitch positive bow up, heading clockwise from true north.
// * HDT: heading in degrees true (field 1), 'T' (field 2).
// * PHTRO (iXblue "Octans/PHINS standard" output, SMC IMU manual 4.2.21): pitch magnitude with
//   'M' bow up / 'P' bow down, roll magnitude with 'B' port down / 'T' port up.
// * PIXSE,ATITUD,roll,pitch: iXblue convention roll positive port up (= starboard down, same as
//   ours) and pitch positive bow down (opposite to ours; see NmeaOptions). This follows from the
//   iXblue vehicle frame XV1 bow, XV2 port, XV3 up with right-handed rotations (Octans "AHRS
//   Advanced Configuration" guide MU-AHRS-AN-002, appendix B "Orientation and sign conventions").
// * PIXSE,HEADNG,x.xxx: heading in degrees. Not found in the iXblue documents available when
//   this was written; decoded as a single true-heading field like HDT.
// * PIXSE,POSITI,lat_deg,lon_deg,altitude_m; PIXSE,SPEED_,east,north,up in m/s;
//   PIXSE,STDHRP heading/roll/pitch std in deg; STDPOS lat/lon/altitude std in m;
//   STDSPD east/north/up std in m/s; STATUS/ALGSTS two 32-bit hex words (LSB word first).
// None of these sentences carry a time of validity: Timestamps::sensor_time_us stays empty.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

/// Which sentence a record came from.
enum class NmeaSentence : uint8_t {
  kHdt,
  kPhtro,
  kIxseAtitud,
  kIxseHeadng,
  kIxsePositi,
  kIxseSpeed,
  kIxseStdhrp,
  kIxseStdpos,
  kIxseStdspd,
  kIxseStatus,
  kIxseAlgsts,
};

/// Sentence name as on the wire ("HDT", "PHTRO", "PIXSE,ATITUD", ...).
std::string_view to_string(NmeaSentence sentence);

/// True heading (HDT, PIXSE HEADNG).
struct NmeaHeading {
  Timestamps time;
  NmeaSentence sentence = NmeaSentence::kHdt;
  std::array<char, 2> talker{'H', 'E'};  ///< HDT talker id (e.g. "HE", "GP"); "IX" for PIXSE
  double heading_rad = 0.0;              ///< clockwise from true north, (-pi, pi]
};

/// Roll and pitch (PHTRO, PIXSE ATITUD), body FRD in NED.
struct NmeaAttitude {
  Timestamps time;
  NmeaSentence sentence = NmeaSentence::kPhtro;
  double roll_rad = 0.0;   ///< positive starboard down
  double pitch_rad = 0.0;  ///< positive bow up
};

/// Geographic position (PIXSE POSITI).
struct NmeaPosition {
  Timestamps time;
  double latitude_rad = 0.0;
  double longitude_rad = 0.0;
  std::optional<double> altitude_m;  ///< positive up (iXblue altitude; depth is negative)
};

/// Velocity over ground in NED (PIXSE SPEED_, sent as east, north, up).
struct NmeaVelocity {
  Timestamps time;
  std::array<double, 3> v_ned_mps{};
};

/// Attitude standard deviations (PIXSE STDHRP).
struct NmeaAttitudeStd {
  Timestamps time;
  double heading_std_rad = 0.0;
  double roll_std_rad = 0.0;
  double pitch_std_rad = 0.0;
};

/// Position standard deviations (PIXSE STDPOS).
struct NmeaPositionStd {
  Timestamps time;
  double north_std_m = 0.0;  ///< latitude std
  double east_std_m = 0.0;   ///< longitude std
  double altitude_std_m = 0.0;
};

/// Velocity standard deviations in NED (PIXSE STDSPD, sent as east, north, up).
struct NmeaVelocityStd {
  Timestamps time;
  std::array<double, 3> v_ned_std_mps{};
};

/// iXblue status words (PIXSE STATUS: system status, ALGSTS: algorithm status).
struct NmeaStatus {
  Timestamps time;
  NmeaSentence sentence = NmeaSentence::kIxseStatus;
  uint64_t word = 0;  ///< (MSB word << 32) | LSB word
};

using NmeaRecord = std::variant<NmeaHeading, NmeaAttitude, NmeaPosition, NmeaVelocity,
                                NmeaAttitudeStd, NmeaPositionStd, NmeaVelocityStd, NmeaStatus>;

struct NmeaOptions {
  /// Sentences without "*hh" are accepted when false, rejected (counted malformed) when true.
  bool require_checksum = true;
  /// Length limit in characters including '$' and CR LF: 82 per NMEA 0183; range [12, 4096].
  std::size_t max_sentence_chars = 82;
  /// Limit for proprietary sentences ($P...), >= max_sentence_chars, <= 4096.
  std::size_t max_proprietary_sentence_chars = 160;
  /// iXblue PIXSE ATITUD pitch is positive bow down (iXblue convention); set false for an
  /// installation configured to output pitch positive bow up.
  bool ixblue_pitch_positive_bow_down = true;
  /// Speeds above this magnitude (m/s) are rejected as out of range; range (0, 1000].
  double max_speed_mps = 50.0;

  /// Empty when valid, otherwise what is wrong.
  std::string validate() const;
};

/// Streaming NMEA decoder (see file comment). Not thread-safe; one instance per stream.
class NmeaDecoder {
 public:
  explicit NmeaDecoder(NmeaOptions options = {});
  ~NmeaDecoder();
  NmeaDecoder(NmeaDecoder&&) noexcept;
  NmeaDecoder& operator=(NmeaDecoder&&) noexcept;

  /// Decodes `bytes` (any chunking) and appends every completed record to `out`.
  void feed(std::span<const uint8_t> bytes, const HostTime& received, std::vector<NmeaRecord>& out);
  const DecodeStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Wraps `body` (text between '$' and '*') as "$body*hh\r\n".
std::string nmea_wrap(std::string_view body);

/// Encodes `record` as its sentence with checksum and CR LF (degrees with 3 decimals, position
/// with 8). Inverse of NmeaDecoder for values within the decoder's ranges.
std::string encode_nmea(const NmeaRecord& record, const NmeaOptions& options = {});

}  // namespace nav::drivers

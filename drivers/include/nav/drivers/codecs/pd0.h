#pragma once
// Teledyne RDI PD0 ("WorkHorse Commands and Output Data Format", ch. "PD0 Output Format"):
// binary ensembles from WorkHorse / Navigator / Pathfinder DVLs and ADCPs, and the PD0 files
// WinRiver II writes. A streaming decoder (bytes in, ensembles out) and an encoder.
//
// Ensemble layout (all little-endian): header (0x7F 0x7F, ensemble byte count N excluding the
// checksum, spare, number of data types (one byte: 1..255), offset table), data types located by
// the offset table, then a 2-byte checksum = sum of the N bytes mod 65536. Decoded data types:
// fixed leader 0x0000, variable leader 0x0080, bottom track 0x0600. Profiles (velocity 0x0100,
// correlation 0x0200, echo intensity 0x0300, percent good 0x0400, status 0x0500) and any
// other type (WinRiver writes one navigation type 0x2022 per GPS fix, so its ensembles can hold
// tens of types; Sentinel V, ...) are skipped by the offset table, listed in
// `Pd0Ensemble::skipped_type_ids` and counted in `Pd0Decoder::skipped_types()`.
//
// Conventions: SI units and radians; values absent, flagged invalid by the instrument
// (-32768 velocity, 0 range) or outside the documented range are empty optionals. Bottom-track
// velocities are as PD0 writes them, in `coord_frame`, beams 1..4 or (X,Y,Z,error) or
// (E,N,U,error); PD0 bottom-track velocity is the velocity of the bottom relative to the
// instrument (the manual: "assumes the instrument is stationary and the bottom is moving").

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

/// Coordinate frame of velocities, from the fixed leader's coordinate-transform byte (EX
/// command) bits 4-3: 00 beam, 01 instrument, 10 ship, 11 earth.
enum class Pd0CoordFrame : uint8_t { kBeam = 0, kInstrument = 1, kShip = 2, kEarth = 3 };

/// "beam", "instrument", "ship" or "earth".
const char* to_string(Pd0CoordFrame frame);

/// Fixed leader (data type 0x0000): the instrument's configuration.
struct Pd0FixedLeader {
  uint8_t firmware_version = 0;
  uint8_t firmware_revision = 0;
  uint16_t system_config = 0;  ///< raw bit field (frequency, beam pattern, up/down, angle)
  uint8_t num_beams = 4;
  uint8_t num_cells = 0;
  uint16_t pings_per_ensemble = 0;
  double cell_length_m = 0.0;     ///< depth cell length (WS), cm on the wire
  double blank_m = 0.0;           ///< blank after transmit (WF), cm on the wire
  double bin1_distance_m = 0.0;   ///< distance to the middle of the first cell, cm on the wire
  uint8_t coord_transform = 0;    ///< raw EX byte (frame bits 4-3, tilts 2, 3-beam 1, mapping 0)
  uint8_t sensor_source = 0;      ///< raw EZ byte
  uint8_t sensors_available = 0;  ///< raw byte
  uint32_t serial_number = 0;     ///< 0 when the leader is too short to carry it
  uint8_t beam_angle_deg = 0;     ///< 0 when the leader is too short to carry it

  Pd0CoordFrame coord_frame() const { return Pd0CoordFrame((coord_transform >> 3) & 0x3); }
  bool tilts_used() const { return (coord_transform & 0x04) != 0; }
  bool three_beam_used() const { return (coord_transform & 0x02) != 0; }
  bool bin_mapping_used() const { return (coord_transform & 0x01) != 0; }
};

/// Bottom track (data type 0x0600), per beam slot 1..4.
struct Pd0BottomTrack {
  uint16_t pings_per_ensemble = 0;
  /// Velocity in the ensemble's coordinate frame (mm/s on the wire, -32768 = invalid).
  std::array<std::optional<double>, 4> velocity_mps{};
  /// Vertical range to the bottom per beam (cm on the wire, LSB word plus the MSB byte of
  /// 65536 cm when the type carries it; 0 = no bottom detected -> empty).
  std::array<std::optional<double>, 4> range_m{};
  std::array<uint8_t, 4> correlation{};     ///< 0-255 counts
  std::array<uint8_t, 4> eval_amplitude{};  ///< 0-255 counts
  std::array<uint8_t, 4> percent_good{};    ///< 0-100 %

  /// True when all four velocity values are valid.
  bool velocity_valid() const;
};

/// One decoded PD0 ensemble.
struct Pd0Ensemble {
  /// sensor_time_us: the RTC time of the ensemble (UTC, microseconds since 1970), from the Y2K
  /// RTC fields when present, else from the 2-digit-year RTC (years 80-99 -> 19xx, else 20xx);
  /// empty when the RTC fields are out of range.
  Timestamps time;
  uint32_t ensemble_number = 0;  ///< LSB word + MSB byte * 65536
  Pd0FixedLeader fixed;
  std::optional<double> heading_rad;  ///< [0, 2pi), 0.01 deg on the wire (EH)
  /// Tilt 1 as reported, [-pi/2, pi/2], 0.01 deg signed (EP); not converted to "real pitch"
  /// (the manual's atan(tan(tilt1) cos(tilt2))) nor corrected for an up-looking instrument.
  std::optional<double> pitch_rad;
  std::optional<double> roll_rad;         ///< tilt 2, [-pi/2, pi/2], 0.01 deg signed (ER)
  std::optional<double> temperature_c;    ///< 0.01 degC signed (ET)
  std::optional<double> salinity_ppt;     ///< ppt (ES)
  std::optional<double> sound_speed_mps;  ///< m/s (EC)
  std::optional<double> depth_m;          ///< depth of transducer, dm on the wire (ED)
  std::optional<double> pressure_dbar;    ///< daPa (signed) on the wire; absent in short leaders
  uint16_t bit_result = 0;                ///< built-in test result word, 0 = all passed
  std::optional<Pd0BottomTrack> bottom_track;
  std::vector<uint16_t> skipped_type_ids;  ///< data types present but not decoded

  Pd0CoordFrame coord_frame() const { return fixed.coord_frame(); }
};

/// Decoder options (plain struct; `validate()` is checked by the constructor).
struct Pd0DecoderOptions {
  /// Largest ensemble accepted, in bytes including the checksum. A header announcing more is
  /// treated as a false header (counted malformed) and the search goes on. PD0's byte count is
  /// 16 bits, so 65537 accepts everything; smaller values bound the wait on a false header.
  std::size_t max_ensemble_bytes = 65537;

  /// True when the options are usable (max_ensemble_bytes >= 64).
  bool validate() const;
};

/// Data types of the emitted ensembles that were not decoded (Pd0Ensemble::skipped_type_ids).
struct Pd0SkippedTypes {
  uint64_t total = 0;    ///< every skipped data type, repeats of a decoded ID included
  uint64_t unknown = 0;  ///< of which IDs outside the WorkHorse PD0 table (WinRiver 0x2000+, ...)
};

/// Streaming PD0 decoder. Feed arbitrary chunks; complete, checksum-valid ensembles are
/// appended to `out`. Resynchronisation: on a bad checksum or malformed header the decoder
/// drops one byte and searches for the next 0x7F 0x7F. A header is believed (and the decoder
/// waits for its N bytes) only when its offset table is consistent: first offset right after
/// the table and pointing at the fixed leader ID 0x0000, offsets increasing and inside N, as
/// every RDI instrument writes them; this keeps a 0x7F7F in garbage from stalling output. Any
/// number of data types the format can carry (1..255) is accepted. Every byte fed ends up
/// either in an emitted ensemble, in `stats().dropped_bytes`, or (at most one incomplete
/// ensemble) in `buffered_bytes()`. stats().out_of_range counts ensembles in which at
/// least one value was rejected by its range check; such an ensemble is still emitted with those
/// values empty. An emitted ensemble's host time is the `received` of the feed() call that
/// completed it. Not thread-safe; one decoder per stream.
class Pd0Decoder {
 public:
  explicit Pd0Decoder(Pd0DecoderOptions options = {});

  void feed(std::span<const uint8_t> bytes, const HostTime& received,
            std::vector<Pd0Ensemble>& out);
  const DecodeStats& stats() const { return stats_; }
  const Pd0SkippedTypes& skipped_types() const { return skipped_types_; }
  /// Bytes held waiting for the rest of an ensemble.
  std::size_t buffered_bytes() const { return buffer_.size() - start_; }

 private:
  enum class Step { kNeedMore, kDropOne, kEmitted };
  Step try_decode(const HostTime& received, std::vector<Pd0Ensemble>& out);
  void drop(std::size_t n);
  void compact();

  Pd0DecoderOptions options_;
  std::vector<uint8_t> buffer_;
  std::size_t start_ = 0;  ///< first unconsumed byte of buffer_
  DecodeStats stats_;
  Pd0SkippedTypes skipped_types_;
};

/// Outcome of decoding one ensemble.
enum class Pd0ParseError {
  kNone,         ///< decoded, every value within range
  kMalformed,    ///< inconsistent offset table or a data type too short for its fields
  kUnsupported,  ///< well formed but without a fixed and a variable leader (not usable)
  kOutOfRange,   ///< decoded; some values were outside their range and left empty
};

/// Decodes one complete ensemble (header to checksum inclusive; the checksum is not checked
/// here). Values outside their documented range are left empty and counted in
/// `out_of_range_fields`. `out` is usable only for kNone and kOutOfRange. The offset table is
/// read on the stack; the only allocation is `out.skipped_type_ids` (at most 253 IDs).
Pd0ParseError parse_pd0_ensemble(std::span<const uint8_t> ensemble, Pd0Ensemble& out,
                                 int& out_of_range_fields);

/// Encodes header + fixed leader (59 bytes) + variable leader (65 bytes, Y2K RTC) + bottom
/// track (85 bytes, range MSB bytes) when present + checksum; skipped types are not written.
/// Empty optionals are written as the instrument's invalid marker (-32768 velocity, 0 range)
/// or, for leader values PD0 has no marker for, as an out-of-range raw value, so that they
/// decode empty again (an empty pressure, which only short leaders produce, is written 0).
/// sensor_time_us sets both RTC fields (empty -> all zero, which decodes as no time).
std::vector<uint8_t> encode_pd0(const Pd0Ensemble& ensemble);

/// A data type written verbatim: its 2-byte ID, then `body`.
struct Pd0RawDataType {
  uint16_t id = 0;
  std::vector<uint8_t> body;  ///< the bytes after the ID
};

/// As encode_pd0(ensemble), with `extra` data types written after the decoded ones, in order
/// (as WinRiver appends its types). Throws std::invalid_argument when the ensemble would hold
/// more than 255 data types or more than 65535 bytes before the checksum, or when an extra type
/// has the bottom-track ID and `ensemble` has no bottom track (it would be decoded as one).
std::vector<uint8_t> encode_pd0(const Pd0Ensemble& ensemble, std::span<const Pd0RawDataType> extra);

/// Sum of bytes mod 65536 (the PD0 checksum).
uint16_t pd0_checksum(std::span<const uint8_t> bytes);

}  // namespace nav::drivers

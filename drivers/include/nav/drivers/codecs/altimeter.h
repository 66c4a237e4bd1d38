#pragma once
// Acoustic altimeter ASCII outputs, one protocol per decoder chosen by AltimeterFormat:
// * kTritechPa500: "ddd.ddm<CR><LF>" (Tritech PA500 and the many altimeters emulating it),
//   range in metres with a trailing 'm'.
// * kValeportNmea: Valeport VA500 "$PRVAT,xx.xxx,M,xxxx.xxx,dBar*hh" (VA500 manual section
//   4.1): range (m) and, with the optional pressure sensor, pressure (dbar). A pressure
//   outside [-20, 12000] dbar (beyond the deepest ocean) makes the sentence malformed.
// * kImpactSubseaIsa500: ISA500 ASCII string, default "ddd.ddd m" or a user-defined string
//   with a fixed prefix and suffix around the number (AltimeterFormat::prefix / suffix).
// * kNmeaDbt: NMEA 0183 "$--DBT,x.x,f,x.x,M,x.x,F*hh" depth below transducer (any talker; the
//   VA500's $SDDBT mode); metres field, else feet or fathoms.
// A reading equal to one of the no-echo sentinels (e.g. 0 or 99.99) is reported with
// status kNoEcho and no range; a reading outside [min_range_m, max_range_m] with status
// kOutOfRange (also counted in DecodeStats::out_of_range) and no range. No time of validity
// in these outputs (sensor_time_us stays empty).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

enum class AltimeterProtocol { kTritechPa500, kValeportNmea, kImpactSubseaIsa500, kNmeaDbt };

struct AltimeterFormat {
  AltimeterProtocol protocol = AltimeterProtocol::kTritechPa500;
  /// ISA500 custom string: text before and after the number (after trimming blanks).
  std::string prefix;
  std::string suffix = "m";
  /// Valid measuring range of the instrument (m); readings outside are flagged.
  double min_range_m = 0.1;
  double max_range_m = 300.0;
  /// Readings equal (within 1e-6 m) to one of these mean "no bottom echo".
  std::vector<double> no_echo_values_m = {0.0, 99.99, 999.99};
  /// NMEA forms: accept sentences without "*hh".
  bool require_checksum = true;
  /// Longest accepted record in characters: plain lines without their terminator, NMEA
  /// sentences including '$' and CR LF (82 per NMEA 0183); range [8, 256].
  std::size_t max_line_chars = 82;

  std::string validate() const;
};

enum class AltimeterStatus : uint8_t { kValid, kNoEcho, kOutOfRange };

struct AltimeterRecord {
  Timestamps time;
  AltimeterStatus status = AltimeterStatus::kValid;
  std::optional<double> range_m;      ///< only when status is kValid
  std::optional<double> pressure_pa;  ///< Valeport $PRVAT with the pressure sensor fitted
  double raw_value_m = 0.0;           ///< the reading as sent (also for no echo/out of range)
};

class AltimeterDecoder {
 public:
  explicit AltimeterDecoder(AltimeterFormat format = {});
  ~AltimeterDecoder();
  AltimeterDecoder(AltimeterDecoder&&) noexcept;
  AltimeterDecoder& operator=(AltimeterDecoder&&) noexcept;

  void feed(std::span<const uint8_t> bytes, const HostTime& received,
            std::vector<AltimeterRecord>& out);
  const DecodeStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The instrument's output line for `record.raw_value_m` (and pressure) in `format`.
std::string encode_altimeter(const AltimeterRecord& record, const AltimeterFormat& format = {});

}  // namespace nav::drivers

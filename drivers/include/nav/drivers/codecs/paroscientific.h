#pragma once
// Paroscientific Digiquartz intelligent transmitters (RS-232/RS-485 series 6000/9000/1000,
// "Digiquartz Programming and Operation Manual", section "Command and response format"):
// every reply is `*DDSS<data><CR><LF>` where DD is the destination id (00 = host) and SS the
// source id (01..98, the transmitter). Pressure replies to the P3 (single sample) and P4
// (continuous) commands carry the pressure as a decimal number in the unit chosen with the UN
// command: 1 psi, 2 hPa/mbar, 3 bar, 4 kPa, 5 MPa, 6 inHg, 7 mmHg/Torr, 8 mH2O (0 = user
// factor UF, given here as a custom factor). A host command echoed on the line
// ("*0100P3") is recognised and counted as unsupported. Absolute sensors read psia. Values go
// out in pascal. No time of validity in these replies (sensor_time_us stays empty).

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

enum class ParoPressureUnit {
  kPsi,     ///< UN1 (psia for absolute sensors): 6894.757293168 Pa
  kHpa,     ///< UN2, hPa = mbar: 100 Pa
  kBar,     ///< UN3: 1e5 Pa
  kKpa,     ///< UN4: 1e3 Pa
  kMpa,     ///< UN5: 1e6 Pa
  kInHg,    ///< UN6, inches of mercury at 0 degC: 3386.389 Pa
  kMmHg,    ///< UN7, mmHg = Torr: 133.322368 Pa
  kMH2O,    ///< UN8, metres of water at 4 degC: 9806.65 Pa
  kDbar,    ///< decibar (user factor, common in oceanography): 1e4 Pa
  kPascal,  ///< Pa (user factor)
  kCustom,  ///< UN0 with ParoOptions::custom_pa_per_unit
};

/// Pascal per unit of `unit` (custom -> `custom_pa_per_unit`).
double pascal_per_unit(ParoPressureUnit unit, double custom_pa_per_unit = 1.0);

struct ParoOptions {
  ParoPressureUnit unit = ParoPressureUnit::kPsi;
  double custom_pa_per_unit = 1.0;  ///< used with kCustom only, > 0
  /// Accept replies from this transmitter id only (1..98); empty accepts any source.
  std::optional<int> source_id;
  /// Accepted pressure range in Pa: absolute transmitters read >= 0; a gauge transmitter may
  /// read slightly negative at the surface. Digiquartz full scales reach 276 MPa (40 kpsi).
  double min_pressure_pa = -1.1e5;
  double max_pressure_pa = 2.8e8;
  /// Longest accepted reply line without terminator; range [8, 256].
  std::size_t max_line_chars = 40;

  std::string validate() const;
};

struct ParoRecord {
  Timestamps time;
  int destination_id = 0;  ///< DD
  int source_id = 1;       ///< SS, the transmitter
  double pressure_pa = 0.0;
};

class ParoDecoder {
 public:
  explicit ParoDecoder(ParoOptions options = {});
  ~ParoDecoder();
  ParoDecoder(ParoDecoder&&) noexcept;
  ParoDecoder& operator=(ParoDecoder&&) noexcept;

  void feed(std::span<const uint8_t> bytes, const HostTime& received, std::vector<ParoRecord>& out);
  const DecodeStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Poll reply "*DDSS<value>\r\n" for `record` in the unit of `options` with `decimals` digits.
std::string encode_paro_reply(const ParoRecord& record, const ParoOptions& options = {},
                              int decimals = 4);

/// Host command "*DDSS<command>\r\n", e.g. encode_paro_command(1, "P3") -> "*0100P3\r\n".
std::string encode_paro_command(int transmitter_id, const std::string& command);

}  // namespace nav::drivers

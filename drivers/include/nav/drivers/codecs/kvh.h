#pragma once
// KVH DSP-3000 fibre-optic gyro, ASCII output (KVH DSP-3000 Technical Manual, "Data output
// format", ASCII mode): one line per sample, `<value><spaces><status><CR><LF>`, e.g.
// "   0.0123456   1". The value is, depending on the mode selected with the R / A / P commands,
// the rotation rate (deg/s), the incremental angle since the previous sample (deg) or the
// integrated angle since the last zeroing (deg); the status is '1' valid, '0' invalid (start-up,
// fault). Positive values are clockwise about the sensor axis looking down its arrow (the
// sensor +z axis, right-handed). Lines are the only framing: the decoder resynchronises on line
// breaks. The DSP-3000 has no time of validity in ASCII mode (sensor_time_us stays empty).

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

enum class KvhOutputMode {
  kRate,              ///< deg/s ("R" command)
  kIncrementalAngle,  ///< deg since the previous sample ("A" command)
  kIntegratedAngle,   ///< deg since the last zero ("P" command)
};

enum class KvhAngleUnit { kDegrees, kRadians };

struct KvhOptions {
  KvhOutputMode mode = KvhOutputMode::kRate;
  /// Unit of the value on the wire (degrees by default; some firmware outputs radians).
  KvhAngleUnit unit = KvhAngleUnit::kDegrees;
  /// Rates (and incremental angles per sample) above this magnitude are rejected: the
  /// DSP-3000 input range is +-375 deg/s. (rad/s, > 0)
  double max_rate_radps = 375.0 * 3.14159265358979323846 / 180.0;
  /// Integrated angles above this magnitude are rejected (rad, > 0).
  double max_integrated_angle_rad = 1.0e6;
  /// Longest accepted line without terminator; range [8, 256].
  std::size_t max_line_chars = 40;

  std::string validate() const;
};

struct KvhRecord {
  Timestamps time;
  KvhOutputMode mode = KvhOutputMode::kRate;
  bool sensor_valid = false;         ///< status flag '1'
  std::optional<double> rate_radps;  ///< kRate and valid
  std::optional<double> angle_rad;   ///< incremental or integrated angle, valid
};

class KvhDecoder {
 public:
  explicit KvhDecoder(KvhOptions options = {});
  ~KvhDecoder();
  KvhDecoder(KvhDecoder&&) noexcept;
  KvhDecoder& operator=(KvhDecoder&&) noexcept;

  void feed(std::span<const uint8_t> bytes, const HostTime& received, std::vector<KvhRecord>& out);
  const DecodeStats& stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One output line for `record` in the units of `options` ("%13.7f %d\r\n" layout); an
/// invalid record is written with value 0 and status '0'.
std::string encode_kvh(const KvhRecord& record, const KvhOptions& options = {});

}  // namespace nav::drivers

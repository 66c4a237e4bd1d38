#pragma once
// Simulated navigation sensors that write the bytes the real instruments send
// (hil-tests/README.md "Protocol per sensor type"): RDI PD0 bottom-track ensembles (5 Hz),
// iXblue Octans $HEHDT + $PHTRO (10 Hz), Paroscientific pressure replies in psia (2 Hz),
// Tritech PA500 altimeter lines (5 Hz). Measurements come from the truth through the config's
// mounts (the DVL measures the velocity of its own location in its own frame; the depth sensor
// the depth of its lever arm; the altimeter the range along its axis to the seafloor) with the
// config's noise sigmas, optional small biases, DVL bottom-lock dropouts, and host times = time of
// validity + the sensor's config latency + jitter. The PD0 RTC is the DVL's own clock: true
// UTC + an offset + a drift.

#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/daemon/config/config.h"
#include "nav/sim/seafloor.h"

namespace nav::sim {

/// Clocks of the simulated dive (hil-tests/README.md "Clocks").
inline constexpr std::int64_t kDiveStartRealtimeUs = 1086048000000000;  // 2004-06-01T00:00:00Z
inline constexpr std::int64_t kDiveStartMonotonicUs = 1000000000;       // 1,000 s
inline std::int64_t realtime_of(std::int64_t monotonic_us) {
  return kDiveStartRealtimeUs + (monotonic_us - kDiveStartMonotonicUs);
}

/// Sensor errors beyond white noise. Defaults are small; every one may be set to 0.
struct SensorErrorOptions {
  // Constant offsets a vehicle calibrates out before the dive (pressure zeroed at the surface,
  // dockside heading calibration) and the DVL scale factor are 0 by default: the filter models
  // white noise only, so the default dive is the consistency scenario (hil-tests/README.md).
  // with_sensor_biases() (`navtool simulate --sensor-biases`) gives the uncalibrated vehicle.
  double dvl_scale_error = 0.0;      ///< velocity scale factor error (with_sensor_biases: 0.1 %)
  double heading_bias_rad = 0.0;     ///< added to every heading (with_sensor_biases: 0.05 deg)
  double roll_pitch_bias_rad = 0.0;  ///< added to roll and pitch (with_sensor_biases: 0.02 deg)
  double depth_bias_m = 0.0;         ///< pressure-sensor offset in depth (with_sensor_biases: 0.02)
  double altitude_bias_m = 0.0;
  double dvl_clock_offset_s = 0.37;    ///< DVL RTC minus true UTC at the dive start
  double dvl_clock_drift_ppm = 20.0;   ///< DVL RTC rate error
  double dvl_dropouts_per_hour = 1.5;  ///< bottom-lock losses (at least one if > 0)
  double dvl_dropout_min_s = 10.0, dvl_dropout_max_s = 40.0;
  double jitter_ms = 2.0;         ///< host receive jitter, uniform [0, jitter]
  double serial_baud = 115200.0;  ///< for the gap between back-to-back sentences
  /// Zero every bias, clock error and dropout (white noise and latency stay).
  static SensorErrorOptions ideal();
  /// The defaults plus uncalibrated constant errors: DVL scale factor 0.1 %, heading bias
  /// 0.05 deg, roll/pitch bias 0.02 deg, depth bias 0.02 m.
  static SensorErrorOptions with_sensor_biases();
  /// Empty when usable, else "<field>: <reason>".
  std::string validate() const;
};

/// The bytes of one read from a sensor, stamped with the host clocks.
struct RawEvent {
  std::int64_t host_monotonic_us = 0;
  std::string sensor;  ///< config name
  std::vector<std::uint8_t> bytes;
};

struct SensorCounts {
  std::int64_t dvl_ensembles = 0, dvl_invalid_ensembles = 0;
  std::int64_t heading_sentences = 0, attitude_sentences = 0;
  std::int64_t depth_replies = 0, altimeter_lines = 0;
};

class SensorStreams {
 public:
  /// Uses the first sensor of each type dvl_pd0, heading_nmea, pressure_paro, altimeter in the
  /// config (throws std::invalid_argument naming a missing type). `dive_duration_s` places the
  /// dropouts.
  SensorStreams(const daemon::NavdConfig& config, const SensorErrorOptions& errors,
                const Seafloor& seafloor, double dive_duration_s, std::uint64_t seed);

  /// Samples every sensor due at `t_us` (monotonic; multiples of 50 ms from the dive start)
  /// from the truth `x` and appends its bytes.
  void sample(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out);

  const SensorCounts& counts() const { return counts_; }
  /// Dropout intervals [start, end) in seconds since the dive start.
  const std::vector<std::pair<double, double>>& dvl_dropouts() const { return dropouts_; }
  /// DVL RTC time (µs since 1970, the DVL's clock) at monotonic time t_us, before rounding.
  std::int64_t dvl_clock_us(std::int64_t t_us) const;

 private:
  struct Stream {
    const daemon::SensorConfig* config = nullptr;
    std::mt19937_64 rng;
  };
  std::int64_t host_time(Stream& s, std::int64_t t_us);
  void sample_dvl(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out);
  void sample_heading(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out);
  void sample_depth(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out);
  void sample_altimeter(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out);
  double gauss(Stream& s, double sigma);

  SensorErrorOptions errors_;
  const Seafloor* seafloor_;
  Stream dvl_, heading_, depth_, altimeter_;
  std::vector<std::pair<double, double>> dropouts_;
  std::uint32_t ensemble_number_ = 0;
  SensorCounts counts_;
};

/// Sea pressure (dbar) whose UNESCO 1983 depth at `latitude_rad` is depth_m (inverse of
/// drivers::unesco1983_depth_m by Newton iteration, |error| < 1e-9 m).
double unesco1983_sea_pressure_dbar(double depth_m, double latitude_rad);

/// Independent random stream `stream` of a seed (splitmix64), so components do not share draws.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream);

/// The first sensor of `type` in the config, or nullptr.
const daemon::SensorConfig* find_sensor(const daemon::NavdConfig& config, daemon::SensorType type);

}  // namespace nav::sim

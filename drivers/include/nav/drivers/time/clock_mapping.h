#pragma once
// Mapping a sensor's own clock (its time of validity, e.g. a millisecond counter in a CAN
// message) onto the host clock, for one sensor.
//
// Model: host_us = sensor_us + offset + drift * (sensor_us - ref) + latency, where the receive
// latency is >= 0 and jitters (USB/serial/CAN queues, scheduling). Averaging would bias the
// offset by the mean latency and be dragged by spikes; instead, as in one-way clock-skew
// estimation (Moon, Skelly & Towsley, "Estimation and removal of clock skew from network delay
// measurements", INFOCOM 1999; Zhang, Liu & Xia, "Clock synchronization algorithms for network
// measurements", INFOCOM 2002), the line is the LOWER ENVELOPE of the (sensor time, host -
// sensor) points: the line below every point in a sliding window that maximises its height at
// the window's mean sensor time (a linear programme whose optimum is the lower convex-hull
// edge over the mean). Its error is set by the smallest latencies, not the average ones, so
// it is far below the jitter once a window holds a few dozen samples. The drift is bounded
// (|drift| <= max_drift_ppm), which keeps the fit sane over short windows.
//
// Counter wraparound: sensor times are taken modulo `sensor_modulus_us` (e.g. a 16-bit ms
// counter: 65,536,000 us; RTC time of day: 86,400,000,000 us) and unwrapped with the host time
// elapsed since the previous sample, so gaps longer than half a period are still resolved.
// Resets: a sample far BELOW the envelope (impossible for a latency) re-initialises at once; a
// sample far ABOVE it is an outlier unless `reset_confirm_samples` consecutive ones agree
// (sensor reboot or jump backwards), then the mapping restarts from them. Both are counted.
//
// Pure: no clocks, no I/O; the caller passes the host receive time of each sample.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace nav::drivers {

struct ClockMappingOptions {
  /// Period of the sensor clock in µs (counter wraps at this value); 0 = never wraps.
  int64_t sensor_modulus_us = 0;
  /// Samples older than this (sensor time, µs) leave the fit window. Longer windows average
  /// more latency minima; shorter ones follow drift changes (temperature) faster.
  int64_t window_us = 60'000'000;
  /// At most this many samples in the window (the oldest are dropped), >= 2.
  size_t max_samples = 600;
  /// Bound on |drift| (parts per million); crystal oscillators are within ±100 ppm.
  double max_drift_ppm = 200.0;
  /// A sample further than this from the envelope (µs) is a clock jump or latency outlier.
  int64_t jump_threshold_us = 500'000;
  /// Consecutive samples above the envelope by more than jump_threshold_us that mean the
  /// sensor clock jumped backwards (reboot) rather than a latency spike, >= 1.
  size_t reset_confirm_samples = 3;
  /// Known constant part of the latency (µs), subtracted from mapped times.
  int64_t fixed_latency_us = 0;
  /// Resolution of the sensor time (µs), e.g. 1000 for a millisecond counter that truncates:
  /// the true time lies in [reading, reading + resolution), so mapped times add half of it.
  int64_t sensor_resolution_us = 0;

  /// Empty when valid, else the first problem with the field name.
  std::string validate() const;
};

/// What update() did with one sample.
enum class ClockSampleResult {
  kAccepted,  ///< added to the fit
  kOutlier,   ///< far above the envelope, not (yet) trusted, not added
  kReset,     ///< clock jump detected; the mapping restarted from this sample
  kInvalid,   ///< sensor time outside [0, modulus) or host time going backwards
};

struct ClockMappingStats {
  uint64_t samples = 0;  ///< update() calls
  uint64_t accepted = 0;
  uint64_t outliers = 0;
  uint64_t resets = 0;  ///< re-initialisations after a detected jump or reboot
  uint64_t wraps = 0;   ///< counter wraparounds unwrapped
  uint64_t invalid = 0;
};

/// Current linear model: host_us = sensor_unwrapped_us + offset_us + drift * (sensor - ref).
struct ClockFit {
  int64_t ref_sensor_us = 0;     ///< reference point (unwrapped sensor time) of the fit
  int64_t center_sensor_us = 0;  ///< mean sensor time of the window (where the fit is best)
  double offset_us = 0.0;  ///< host - sensor at ref: lower envelope (includes the minimum latency)
  double drift = 0.0;      ///< d(host - sensor)/d(sensor), e.g. 50e-6 for 50 ppm
  size_t samples = 0;      ///< samples in the window
  int64_t span_us = 0;     ///< sensor time covered by the window
  double mean_residual_us = 0.0;  ///< mean latency above the envelope (jitter scale)
};

class ClockMapping {
 public:
  explicit ClockMapping(ClockMappingOptions options = {});

  /// Adds one sample: the sensor's time (wrapped, in [0, modulus) when it wraps) of a message
  /// received at `host_us` (host clock, e.g. CLOCK_MONOTONIC or a kernel time stamp).
  ClockSampleResult update(int64_t sensor_us, int64_t host_us);

  /// Host time of a sensor time near the latest sample (unwrapped to the nearest period), or
  /// nullopt before two samples with distinct sensor times were accepted.
  std::optional<int64_t> to_host_us(int64_t sensor_us) const;
  /// 1-sigma-like uncertainty (µs) of to_host_us at that sensor time: the envelope's expected
  /// height above the true minimum-latency line (mean residual / samples) grown with the
  /// distance from the window centre; nullopt when not initialised.
  std::optional<double> uncertainty_us(int64_t sensor_us) const;

  bool initialised() const { return fit_.has_value(); }
  const std::optional<ClockFit>& fit() const { return fit_; }
  const ClockMappingStats& stats() const { return stats_; }
  const ClockMappingOptions& options() const { return options_; }
  /// Forgets every sample (e.g. on a known sensor restart); stats are kept.
  void clear();

 private:
  struct Sample {
    int64_t sensor_us;  ///< unwrapped
    int64_t host_us;
  };
  /// Unwrapped sensor time of a wrapped one, chosen closest to `expected_us`.
  int64_t unwrap(int64_t sensor_us, int64_t expected_us) const;
  void restart_from(const Sample& s);
  void refit();
  double envelope_at(int64_t sensor_unwrapped_us) const;

  ClockMappingOptions options_;
  std::vector<Sample> window_;           ///< accepted samples, increasing sensor time
  std::vector<Sample> pending_;          ///< consecutive high outliers (possible backwards jump)
  std::vector<double> hull_x_, hull_y_;  ///< scratch for the lower hull
  std::optional<Sample> last_;           ///< latest sample seen (accepted or not)
  std::optional<ClockFit> fit_;
  ClockMappingStats stats_;
};

}  // namespace nav::drivers

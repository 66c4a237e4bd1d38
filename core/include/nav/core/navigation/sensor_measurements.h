#pragma once
// The measurements NavFilter consumes: small owned value types (no heap memory, trivially
// copyable) in one std::variant, each carrying the sensor's time of validity and the host
// receive times (docs/architecture.md "Time"). Frames and units as in core/README.md: sensor-frame
// quantities are rotated into the body by the filter with the sensor's mount
// (NavFilterOptions::sensors, indexed by MeasurementTime::sensor_index).

#include <array>
#include <cstdint>
#include <variant>

namespace nav::core {

/// When a measurement is valid and when it arrived. All in microseconds.
struct MeasurementTime {
  std::int64_t validity_us = 0;        ///< sensor time of validity on the host CLOCK_MONOTONIC
  std::int64_t host_monotonic_us = 0;  ///< CLOCK_MONOTONIC at receipt
  std::int64_t host_realtime_us = 0;   ///< CLOCK_REALTIME at receipt
  std::uint16_t sensor_index = 0;      ///< index into NavFilterOptions::sensors
};

struct DvlVelocity {  ///< bottom-track velocity of the vehicle over ground in the DVL frame
  MeasurementTime time;
  std::array<double, 3> v_sensor_mps{};
};
struct Attitude {  ///< roll, pitch, heading (Z-Y-X Euler) of the sensor frame in world
  MeasurementTime time;
  double roll_rad = 0.0, pitch_rad = 0.0, heading_rad = 0.0;
  bool has_roll_pitch = true;  ///< false: a heading-only sentence (e.g. NMEA HDT)
  bool has_heading = true;     ///< false: a roll/pitch-only sentence (e.g. iXblue PHTRO)
};
struct AngularRate {  ///< gyro rate in the sensor frame
  MeasurementTime time;
  std::array<double, 3> omega_sensor_radps{};
  /// Which components were measured (a single-axis FOG such as the KVH DSP-3000 measures z only;
  /// the others are then 0 and must not be used).
  std::array<bool, 3> has_axis{true, true, true};
};
struct Depth {  ///< depth of the sensor below the surface (world z, down)
  MeasurementTime time;
  double depth_m = 0.0;
};
struct Altitude {  ///< range to the seabed along the sensor axis
  MeasurementTime time;
  double altitude_m = 0.0;
};
struct ImageEvent {  ///< an image was captured (pixels stay with the camera thread)
  MeasurementTime time;
  std::uint64_t frame_id = 0;
};

using Measurement = std::variant<DvlVelocity, Attitude, AngularRate, Depth, Altitude, ImageEvent>;

inline const MeasurementTime& time_of(const Measurement& m) {
  return std::visit([](const auto& x) -> const MeasurementTime& { return x.time; }, m);
}
inline std::int64_t validity_us(const Measurement& m) { return time_of(m).validity_us; }

}  // namespace nav::core

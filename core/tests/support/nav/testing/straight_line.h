#pragma once
// The straight run of the NavFilter tests: a vehicle moving straight north at 0.5 m/s at 100 m
// depth with noise-free DVL, attitude and depth messages and an image every 2 s, and the
// sensors that measure it (DVL, attitude, depth 0.5 m above the reference point, a camera).
#include <cstdint>
#include <vector>

#include "nav/core/navigation/nav_filter_options.h"
#include "nav/core/navigation/sensor_measurements.h"

namespace nav::testing {

inline constexpr double kSpeedMps = 0.5;
inline constexpr double kDepthM = 100.0;

inline core::NavFilterOptions straight_line_options() {
  using namespace core;
  NavFilterOptions o;
  SensorModelOptions dvl, attitude, depth, camera;
  dvl.name = "dvl";
  attitude.name = "attitude";
  depth.name = "depth";
  depth.p_body_sensor_m = Vec3(0.0, 0.0, -0.5);  // 0.5 m above the reference point
  camera.name = "camera";
  camera.p_body_sensor_m = Vec3(0.2, 0.0, 0.3);
  camera.camera = CameraIntrinsics{1000.0, 1000.0, 640.0, 480.0};
  o.sensors = {dvl, attitude, depth, camera};
  o.recovery.mode = RecoveryMode::kFixedIterations;
  o.recovery.iterations_per_step = 5;
  return o;
}

inline core::MeasurementTime at(std::int64_t t_us, std::uint16_t sensor) {
  return core::MeasurementTime{t_us, t_us, 1'700'000'000'000'000 + t_us, sensor};
}

/// Time-ordered messages of the straight run: DVL 5 Hz, attitude 10 Hz, depth 2 Hz, an image
/// every 2 s (altitude 3 m), for `duration_s`.
inline std::vector<core::Measurement> straight_line(double duration_s) {
  using namespace core;
  std::vector<Measurement> out;
  const auto end_us = static_cast<std::int64_t>(duration_s * 1e6);
  for (std::int64_t t = 0; t <= end_us; t += 100'000) {
    out.push_back(Attitude{at(t, 1), 0.0, 0.0, 0.0, true, true});
    if (t % 200'000 == 0) out.push_back(DvlVelocity{at(t + 1'000, 0), {kSpeedMps, 0.0, 0.0}});
    if (t % 500'000 == 0) out.push_back(Depth{at(t + 2'000, 2), kDepthM - 0.5});
    if (t % 2'000'000 == 1'000'000) {
      out.push_back(Altitude{at(t + 3'000, 3), 3.0});
      out.push_back(ImageEvent{at(t + 50'000, 3), static_cast<std::uint64_t>(t / 1000)});
    }
  }
  return out;
}

}  // namespace nav::testing

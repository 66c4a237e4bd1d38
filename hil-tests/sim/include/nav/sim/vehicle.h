#pragma once
// 6-DOF truth of the simulated ROV: simple but realistic dynamics integrated at a fixed tick
// (default 20 Hz). Surge, sway and heave relative to the water follow their commands with a
// first-order lag; the heading controller commands a yaw rate (first-order lag, rate limit);
// roll and pitch are lightly damped oscillators driven by random disturbances, with a lean in
// turns and a pitch-up when climbing; a slowly varying (Ornstein-Uhlenbeck) current adds to
// the velocity over ground. Frames and state order: core/README.md (world NED, body FRD,
// Z-Y-X Euler); the state's velocities are over ground in body axes (what a DVL measures).

#include <cstdint>
#include <random>

#include "nav/core/geometry/types.h"

namespace nav::sim {

struct VehicleOptions {
  double surge_time_constant_s = 3.0;
  double sway_time_constant_s = 3.0;
  double heave_time_constant_s = 2.0;
  double yaw_rate_time_constant_s = 1.5;
  double heading_gain_per_s = 0.4;   ///< yaw rate command per rad of heading error
  double max_yaw_rate_rad_s = 0.17;  ///< ~10 deg/s
  double depth_gain_per_s = 0.35;    ///< heave command per m of depth error
  double max_heave_mps = 0.5;
  double roll_period_s = 7.0, pitch_period_s = 9.0, attitude_damping = 0.15;
  double roll_sigma_rad = 0.012, pitch_sigma_rad = 0.010;  ///< steady oscillation (~0.7 deg)
  double pitch_trim_rad = 0.02;
  double current_mean_mps = 0.03;   ///< mean current speed (random direction from the seed)
  double current_sigma_mps = 0.02;  ///< OU standard deviation per axis
  double current_time_constant_s = 600.0;
};

/// Commands of one tick.
struct VehicleCommand {
  double heading_rad = 0.0;
  double surge_mps = 0.0;
  double depth_m = 0.0;
};

class Vehicle {
 public:
  /// Starts at rest on heading `heading_rad` at world position p (surge already at speed).
  Vehicle(const core::Vec3& p_world_m, double heading_rad, double surge_mps,
          const VehicleOptions& options, std::uint64_t seed);

  /// Integrates one tick of dt_s under the command.
  void step(const VehicleCommand& command, double dt_s);

  /// The 12-element robot state [x y z roll pitch heading u v w p q r].
  core::Vec12 state() const;
  core::Vec3 current_world_mps() const { return current_world_; }

 private:
  VehicleOptions o_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  core::Vec3 p_world_;
  core::Vec3 v_water_body_ = core::Vec3::Zero();  ///< velocity through the water, body axes
  double heading_rad_ = 0.0, yaw_rate_ = 0.0;     ///< heading and its time derivative
  double roll_ = 0.0, roll_rate_ = 0.0;           ///< roll and its time derivative
  double pitch_ = 0.0, pitch_rate_ = 0.0;         ///< pitch and its time derivative
  core::Vec3 current_mean_ = core::Vec3::Zero();
  core::Vec3 current_world_ = core::Vec3::Zero();
};

}  // namespace nav::sim

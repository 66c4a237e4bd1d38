#include "nav/sim/vehicle.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "nav/core/geometry/rotation.h"

namespace nav::sim {
namespace {

/// One step of a damped oscillator x'' = -w^2 (x - target) - 2 zeta w x' + white noise whose
/// intensity gives a steady standard deviation `sigma` around the target.
void oscillator_step(double& x, double& rate, double target, double period_s, double zeta,
                     double sigma, double noise, double dt_s) {
  const double w = 2.0 * std::numbers::pi / period_s;
  const double q = sigma * sigma * 4.0 * zeta * w * w * w;  // white-noise intensity
  rate += (-w * w * (x - target) - 2.0 * zeta * w * rate) * dt_s + std::sqrt(q * dt_s) * noise;
  x += rate * dt_s;
}

}  // namespace

Vehicle::Vehicle(const core::Vec3& p_world_m, double heading_rad, double surge_mps,
                 const VehicleOptions& options, std::uint64_t seed)
    : o_(options), rng_(seed ^ 0xd15ea5e0ULL), p_world_(p_world_m), heading_rad_(heading_rad) {
  v_water_body_.x() = surge_mps;
  pitch_ = o_.pitch_trim_rad;
  std::uniform_real_distribution<double> dir(0.0, 2.0 * std::numbers::pi);
  const double a = dir(rng_);
  current_mean_ << o_.current_mean_mps * std::cos(a), o_.current_mean_mps * std::sin(a), 0.0;
  current_world_ = current_mean_;
}

void Vehicle::step(const VehicleCommand& cmd, double dt_s) {
  // Heading: yaw-rate command from the heading error, first-order yaw-rate response.
  const double err = core::wrap_angle(cmd.heading_rad - heading_rad_);
  const double rate_cmd =
      std::clamp(o_.heading_gain_per_s * err, -o_.max_yaw_rate_rad_s, o_.max_yaw_rate_rad_s);
  const double yaw_accel = (rate_cmd - yaw_rate_) / o_.yaw_rate_time_constant_s;
  yaw_rate_ += yaw_accel * dt_s;
  heading_rad_ = core::wrap_angle(heading_rad_ + yaw_rate_ * dt_s);

  // Velocities through the water: first-order response to surge, zero sway, depth-hold heave.
  const double heave_cmd = std::clamp(o_.depth_gain_per_s * (cmd.depth_m - p_world_.z()),
                                      -o_.max_heave_mps, o_.max_heave_mps);
  v_water_body_.x() += (cmd.surge_mps - v_water_body_.x()) / o_.surge_time_constant_s * dt_s;
  v_water_body_.y() += -v_water_body_.y() / o_.sway_time_constant_s * dt_s;
  v_water_body_.z() += (heave_cmd - v_water_body_.z()) / o_.heave_time_constant_s * dt_s;

  // Roll leans into turns, pitch noses up when climbing (negative heave), both oscillate.
  const double roll_target = 0.3 * yaw_rate_ * v_water_body_.x();
  const double pitch_target = o_.pitch_trim_rad - 0.1 * v_water_body_.z();
  oscillator_step(roll_, roll_rate_, roll_target, o_.roll_period_s, o_.attitude_damping,
                  o_.roll_sigma_rad, normal_(rng_), dt_s);
  oscillator_step(pitch_, pitch_rate_, pitch_target, o_.pitch_period_s, o_.attitude_damping,
                  o_.pitch_sigma_rad, normal_(rng_), dt_s);

  // Current: Ornstein-Uhlenbeck around its mean in the horizontal plane.
  const double tc = o_.current_time_constant_s;
  for (int i = 0; i < 2; ++i) {
    current_world_[i] += -(current_world_[i] - current_mean_[i]) / tc * dt_s +
                         o_.current_sigma_mps * std::sqrt(2.0 * dt_s / tc) * normal_(rng_);
  }

  const core::Vec3 rpy(roll_, pitch_, heading_rad_);
  const core::Mat3 R_world_body = core::rotation_from_euler(rpy);
  p_world_ += (R_world_body * v_water_body_ + current_world_) * dt_s;
}

core::Vec12 Vehicle::state() const {
  const core::Vec3 rpy(roll_, pitch_, heading_rad_);
  const core::Mat3 R_world_body = core::rotation_from_euler(rpy);
  const core::Vec3 v_ground_body = v_water_body_ + R_world_body.transpose() * current_world_;
  const core::Vec3 omega_body =
      core::euler_rate_matrix_inverse(rpy) * core::Vec3(roll_rate_, pitch_rate_, yaw_rate_);
  core::Vec12 x;
  x << p_world_, rpy, v_ground_body, omega_body;
  return x;
}

}  // namespace nav::sim

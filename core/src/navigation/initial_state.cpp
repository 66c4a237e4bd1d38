// The robot's prior at the start of a dive (navigation/initial_state.h).
#include "nav/core/navigation/initial_state.h"

#include <cmath>

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {
constexpr double kInitialSigmaFactor = 10.0;
}  // namespace

bool HeldInitialisation::hold(const Measurement& m, SensorModels& sensors) {
  if (held.empty()) first_time_us = validity_us(m);
  const bool kept = held.size() < kMaxHeld;
  if (kept) held.push_back(m);
  if (const auto* att = std::get_if<Attitude>(&m)) {
    const BodyAttitude body = sensors.body_attitude(*att);
    if (body.has_roll_pitch) {
      roll_pitch = body;
      roll_pitch_sensor = att->time.sensor_index;
    }
    if (body.has_heading) {
      heading = body;
      heading_sensor = att->time.sensor_index;
    }
  } else if (const auto* d = std::get_if<Depth>(&m)) {
    depth = *d;
  }
  return kept;
}

RobotPrior initial_robot_prior(const HeldInitialisation& init, const SensorModels& sensors,
                               const NavFilterOptions& options) {
  const std::size_t depth_sensor = init.depth->time.sensor_index;
  const Vec3 rpy(init.roll_pitch->roll_rad, init.roll_pitch->pitch_rad, init.heading->heading_rad);
  const Vec3 lever = sensors.depth(depth_sensor).p_body_sensor_m;
  RobotPrior prior;
  prior.x0(2) = init.depth->depth_m - (rotation_from_euler(rpy) * lever)(2);
  prior.x0.segment<3>(3) = rpy;
  Vec12 sigma;
  sigma << options.initial_xy_sigma_m, options.initial_xy_sigma_m,
      kInitialSigmaFactor * std::sqrt(sensors.depth_noise(depth_sensor)(0, 0)),
      Vec3::Constant(kInitialSigmaFactor *
                     std::sqrt(sensors.roll_pitch_noise(init.roll_pitch_sensor)(0, 0))),
      Vec3::Constant(options.initial_velocity_sigma_mps),
      Vec3::Constant(options.initial_rate_sigma_radps);
  sigma(5) = kInitialSigmaFactor * std::sqrt(sensors.heading_noise(init.heading_sensor)(0, 0));
  prior.P0 = sigma.array().square().matrix().asDiagonal();
  return prior;
}

}  // namespace nav::core

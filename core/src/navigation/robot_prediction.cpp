// The robot's time update shared by both filters, and the held step
// (navigation/robot_prediction.h).
#include "nav/core/navigation/robot_prediction.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {
/// Attitude sigma added by a held prediction step (robot_prediction.h): half a turn, i.e. lost.
constexpr double kLostAttitudeSigmaRad = std::numbers::pi;
}  // namespace

RobotPrediction held_prediction(const Vec12& x, double dt_s, const ConstantVelocityOptions& noise,
                                double lost_attitude_sigma_rad, double lost_rate_sigma_radps) {
  if (!(std::isfinite(dt_s) && dt_s > 0.0)) {
    throw std::invalid_argument("held_prediction: dt_s = " + std::to_string(dt_s) +
                                " s, expected finite and > 0");
  }
  const Vec3 rpy = x.segment<3>(kRoll);
  const Vec3 v_body = x.segment<3>(kU);
  const Mat3 R_world_body = rotation_from_euler(rpy);

  RobotPrediction out;
  out.x_next = x;
  out.x_next.segment<3>(kX) += dt_s * R_world_body * v_body;
  out.F.block<3, 1>(kX, kRoll) += dt_s * dR_droll(rpy) * v_body;
  out.F.block<3, 1>(kX, kPitch) += dt_s * dR_dpitch(rpy) * v_body;
  out.F.block<3, 1>(kX, kHeading) += dt_s * dR_dheading(rpy) * v_body;
  out.F.block<3, 3>(kX, kU) = dt_s * R_world_body;
  out.x_next.segment<3>(kP).setZero();  // rates restarted (header)
  out.F.block<3, 3>(kP, kP).setZero();

  // Translational noise as the model's (B = R_world_body), the angular block replaced.
  const Mat3 RQa = R_world_body * noise.accel_psd.asDiagonal();
  out.Q.block<3, 3>(kX, kX) = (dt_s * dt_s * dt_s / 3.0) * RQa * R_world_body.transpose();
  out.Q.block<3, 3>(kX, kU) = (dt_s * dt_s / 2.0) * RQa;
  out.Q.block<3, 3>(kU, kX) = out.Q.block<3, 3>(kX, kU).transpose();
  out.Q.block<3, 3>(kU, kU) = dt_s * Mat3(noise.accel_psd.asDiagonal());
  const double displacement_m = 2.0 * dt_s * v_body.norm();
  out.Q.block<3, 3>(kX, kX) += displacement_m * displacement_m * Mat3::Identity();
  for (int k = kRoll; k <= kHeading; ++k) {
    out.Q(k, k) += lost_attitude_sigma_rad * lost_attitude_sigma_rad;
  }
  for (int k = kP; k <= kR; ++k) out.Q(k, k) = lost_rate_sigma_radps * lost_rate_sigma_radps;
  out.Q = 0.5 * (out.Q + out.Q.transpose()).eval();
  return out;
}

RobotPrediction predict_robot(const ConstantVelocityModel& process, const Vec12& x, double dt_s,
                              double lost_rate_sigma_radps) {
  RobotPrediction p;
  try {
    p.x_next = process.predict(x, dt_s, &p.F);
    p.Q = process.process_noise(x, dt_s);
  } catch (const std::domain_error& e) {
    p = held_prediction(x, dt_s, process.options(), kLostAttitudeSigmaRad, lost_rate_sigma_radps);
    p.held_reason = e.what();
  }
  return p;
}

}  // namespace nav::core

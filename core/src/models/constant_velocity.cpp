// Constant-velocity process model, first-order discretisation (constant_velocity.h).

#include "nav/core/models/constant_velocity.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {

void require_valid_dt(double dt_s, const char* where) {
  if (std::isfinite(dt_s) && dt_s > 0.0) return;
  std::ostringstream msg;
  msg << "ConstantVelocityModel::" << where << ": dt_s = " << dt_s << " s, expected finite and > 0";
  throw std::invalid_argument(msg.str());
}

Status check_psd(const Vec3& psd, const char* field) {
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(psd[k]) || psd[k] < 0.0) {
      std::ostringstream msg;
      msg << "ConstantVelocityOptions." << field << "[" << k << "] = " << psd[k]
          << ", expected finite and >= 0";
      return Status::Error(StatusCode::kInvalidArgument, msg.str());
    }
  }
  return Status::Ok();
}

Status check_restoring(const AttitudeRestoringOptions& o) {
  auto bad = [](const char* field, int k, double v, const char* expected) {
    std::ostringstream msg;
    msg << "ConstantVelocityOptions.attitude_restoring." << field;
    if (k >= 0) msg << "[" << k << "]";
    msg << " = " << v << ", expected " << expected;
    return Status::Error(StatusCode::kInvalidArgument, msg.str());
  };
  for (int k = 0; k < 2; ++k) {
    if (!std::isfinite(o.natural_period_s[k]) || o.natural_period_s[k] < 0.0)
      return bad("natural_period_s", k, o.natural_period_s[k], "finite and >= 0");
    if (!std::isfinite(o.damping_ratio[k]) || o.damping_ratio[k] < 0.0)
      return bad("damping_ratio", k, o.damping_ratio[k], "finite and >= 0");
    if (!std::isfinite(o.trim_rad[k])) return bad("trim_rad", k, o.trim_rad[k], "finite");
  }
  if (!std::isfinite(o.pitch_per_heave_rad_per_mps))
    return bad("pitch_per_heave_rad_per_mps", -1, o.pitch_per_heave_rad_per_mps, "finite");
  return Status::Ok();
}

/// One axis's oscillator: omega^2 and 2 zeta omega (0, 0 when its period is 0: random walk).
struct Oscillator {
  double omega2 = 0.0, damping = 0.0;
};

Oscillator oscillator(const AttitudeRestoringOptions& o, int axis) {
  if (!(o.natural_period_s[axis] > 0.0)) return {};
  const double omega = 2.0 * std::numbers::pi / o.natural_period_s[axis];
  return {omega * omega, 2.0 * o.damping_ratio[axis] * omega};
}

/// Adds dt g(x) to the roll and pitch rates of x_next and dt dg/dx to F (file comment).
void add_restoring(const AttitudeRestoringOptions& o, const Vec12& x, double dt_s, Vec12& x_next,
                   Mat12* F) {
  const double c = o.pitch_per_heave_rad_per_mps;
  const double equilibrium[2] = {o.trim_rad[0], o.trim_rad[1] + c * x[kW]};
  for (int axis = 0; axis < 2; ++axis) {
    const Oscillator s = oscillator(o, axis);
    const int angle = kRoll + axis, rate = kP + axis;
    const double offset = wrap_angle(x[angle] - equilibrium[axis]);
    x_next[rate] += dt_s * (-s.omega2 * offset - s.damping * x[rate]);
    if (F == nullptr) continue;
    (*F)(rate, angle) -= dt_s * s.omega2;
    (*F)(rate, rate) -= dt_s * s.damping;
    if (axis == 1) (*F)(rate, kW) += dt_s * s.omega2 * c;
  }
}

}  // namespace

Status ConstantVelocityOptions::validate() const {
  if (Status s = check_psd(accel_psd, "accel_psd"); !s.ok()) return s;
  if (Status s = check_psd(angular_accel_psd, "angular_accel_psd"); !s.ok()) return s;
  return check_restoring(attitude_restoring);
}

ConstantVelocityModel::ConstantVelocityModel(const ConstantVelocityOptions& options)
    : options_(options) {
  if (Status s = options_.validate(); !s.ok()) throw std::invalid_argument(s.message());
}

Vec12 ConstantVelocityModel::predict(const Vec12& x, double dt_s, Mat12* F) const {
  require_valid_dt(dt_s, "predict");
  require_regular_pitch(x[kPitch], "ConstantVelocityModel::predict");
  const Vec3 rpy = x.segment<3>(kRoll);
  const Vec3 v_body = x.segment<3>(kU);
  const Vec3 omega_body = x.segment<3>(kP);
  const Mat3 R_world_body = rotation_from_euler(rpy);
  const Mat3 J2 = euler_rate_matrix(rpy);

  Vec12 x_next = x;
  x_next.segment<3>(kX) += dt_s * R_world_body * v_body;
  x_next.segment<3>(kRoll) += dt_s * J2 * omega_body;
  for (int k = kRoll; k <= kHeading; ++k) x_next[k] = wrap_angle(x_next[k]);

  if (F != nullptr) {
    F->setIdentity();
    F->block<3, 1>(kX, kRoll) += dt_s * dR_droll(rpy) * v_body;
    F->block<3, 1>(kX, kPitch) += dt_s * dR_dpitch(rpy) * v_body;
    F->block<3, 1>(kX, kHeading) += dt_s * dR_dheading(rpy) * v_body;
    F->block<3, 3>(kX, kU) = dt_s * R_world_body;
    F->block<3, 1>(kRoll, kRoll) += dt_s * dJ2_droll(rpy) * omega_body;
    F->block<3, 1>(kRoll, kPitch) += dt_s * dJ2_dpitch(rpy) * omega_body;
    F->block<3, 3>(kRoll, kP) = dt_s * J2;
  }
  if (options_.attitude_restoring.enabled())
    add_restoring(options_.attitude_restoring, x, dt_s, x_next, F);
  return x_next;
}

Mat12 ConstantVelocityModel::process_noise(const Vec12& x, double dt_s) const {
  require_valid_dt(dt_s, "process_noise");
  require_regular_pitch(x[kPitch], "ConstantVelocityModel::process_noise");
  const Vec3 rpy = x.segment<3>(kRoll);
  Mat6 B = Mat6::Zero();
  B.topLeftCorner<3, 3>() = rotation_from_euler(rpy);
  B.bottomRightCorner<3, 3>() = euler_rate_matrix(rpy);
  Vec6 qc;
  qc << options_.accel_psd, options_.angular_accel_psd;
  const Mat6 Qc = qc.asDiagonal();
  const Mat6 BQc = B * Qc;

  Mat12 Q;
  Q.topLeftCorner<6, 6>() = (dt_s * dt_s * dt_s / 3.0) * BQc * B.transpose();
  Q.topRightCorner<6, 6>() = (dt_s * dt_s / 2.0) * BQc;
  Q.bottomLeftCorner<6, 6>() = (dt_s * dt_s / 2.0) * BQc.transpose();
  Q.bottomRightCorner<6, 6>() = dt_s * Qc;
  // Exact symmetry for the information-form update.
  return 0.5 * (Q + Q.transpose());
}

}  // namespace nav::core

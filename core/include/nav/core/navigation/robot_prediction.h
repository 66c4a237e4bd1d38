#pragma once
// The robot's time update, shared by NavFilter (information form, nav_filter.h) and
// DeadReckoningFilter (covariance form, dead_reckoning.h): the same model and the same steps, so
// the two estimate the same thing and differ only in the form they keep it in.
// * predict_robot: the constant-velocity model at the mean (constant_velocity.h), or the held
//   step where the model cannot take it (below).
// * advance_to_measurement: a measurement less than min_step_s after the robot's time is applied
//   at that time; otherwise the gap is predicted in equal steps of at most max_step_s, with no
//   short remainder step (a very short step makes Q's pose block tiny).
//
// The held step, taken when the constant-velocity model cannot step: the mean's pitch is
// beyond +-kMaxAbsPitchRad (rotation.h), where the Euler-rate matrix J2 = d(rpy)/dt / omega
// is singular (cos(pitch) = 0) or the Euler triple has left the principal branch
// |pitch| < 90 deg on which the model and the attitude aids are linearised (Fossen 2011,
// section 2.2.1). Seen live when a replay at 100x real time compressed the vehicle's turns into
// rates of ~1,000 deg/s: one prediction step moved the pitch by more than 90 deg.
//
// Contract: the step is kept (time, delayed states and the published bound advance as after
// any prediction), the estimate's attitude and angular rates are treated as lost, and the
// covariance grows so that it still bounds the error the held step ignores:
//   f(x) = x with  p_world += dt R_world_body(rpy) v_body   (R is regular at every pitch),
//          attitude and body velocities held (no J2), body rates restarted at 0 (the rates
//          that drove the pitch off are not trusted: no sensor measures them in NavFilter);
//   F    = df/dx: identity, except the position rows dt dR/d(roll, pitch, heading) v_body and
//          dt R_world_body (the model's own position rows) and zero rows for the rates;
//   Q    = the model's translational noise with B = R_world_body (constant_velocity.h),
//          plus (2 dt |v_body|)^2 I on the position (the step's displacement is known in
//          length only: |R_true v - R v| <= 2 |v|), plus lost_attitude_sigma_rad^2 on roll,
//          pitch and heading, and lost_rate_sigma_radps^2 on the restarted rates (as at
//          initialisation, nav_filter.h).
// With attitude variances of pi^2 the next roll/pitch and heading aids (residuals wrapped,
// models/measurement.h) bring the attitude back from the sensor in one update, after which the
// model predicts again. The mean is not clamped or re-branched: information-form η encodes the
// mean on its own branch (nav_filter.h, relinearisation), and a clamped pitch near 90 deg
// would put the next step at the singularity.
#include <cstdint>
#include <string>

#include "nav/core/geometry/types.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/status.h"

namespace nav::core {

/// x_{t+dt} ≈ x_next + F (x − x̄), with process noise Q.
struct RobotPrediction {
  Vec12 x_next = Vec12::Zero();
  Mat12 F = Mat12::Identity();
  Mat12 Q = Mat12::Zero();
  std::string held_reason;  ///< why the model's step was held ("": the model's step)
};

/// The held step of the file comment for dt_s > 0 (std::invalid_argument otherwise, naming it);
/// held_reason stays empty.
RobotPrediction held_prediction(const Vec12& x, double dt_s, const ConstantVelocityOptions& noise,
                                double lost_attitude_sigma_rad, double lost_rate_sigma_radps);

/// The model's step from x over dt_s > 0, or the held step (attitude lost: sigma π, rates
/// restarted with lost_rate_sigma_radps) when the model throws std::domain_error. Other
/// exceptions (an invalid dt) propagate.
RobotPrediction predict_robot(const ConstantVelocityModel& process, const Vec12& x, double dt_s,
                              double lost_rate_sigma_radps);

/// Brings time_us to a measurement at t_us: nothing when t_us − time_us < min_step_s (the
/// measurement is applied at time_us); else ceil(gap / max_step_s) equal steps, calling
/// step(dt_s) for each and moving time_us after each success. Returns the first failing
/// step's status.
template <class Step>
Status advance_to_measurement(std::int64_t& time_us, std::int64_t t_us, double min_step_s,
                              double max_step_s, Step&& step);

}  // namespace nav::core

#include <algorithm>
#include <cmath>

namespace nav::core {

template <class Step>
Status advance_to_measurement(std::int64_t& time_us, std::int64_t t_us, double min_step_s,
                              double max_step_s, Step&& step) {
  if (t_us - time_us < static_cast<std::int64_t>(std::llround(min_step_s * 1e6))) {
    return Status::Ok();
  }
  const auto max_step_us =
      std::max<std::int64_t>(1, static_cast<std::int64_t>(std::llround(max_step_s * 1e6)));
  const std::int64_t steps = (t_us - time_us + max_step_us - 1) / max_step_us;
  for (std::int64_t k = 1; k <= steps; ++k) {
    const std::int64_t next_us = time_us + (t_us - time_us) / (steps - k + 1);
    if (Status s = step(static_cast<double>(next_us - time_us) * 1e-6); !s.ok()) return s;
    time_us = next_us;
  }
  return Status::Ok();
}

}  // namespace nav::core

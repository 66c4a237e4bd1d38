#pragma once
// The prediction NavFilter takes when the constant-velocity model cannot: the mean's pitch is
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

#include "nav/core/geometry/types.h"
#include "nav/core/models/constant_velocity.h"

namespace nav::core {

struct HeldPrediction {
  Vec12 x_next = Vec12::Zero();
  Mat12 F = Mat12::Identity();
  Mat12 Q = Mat12::Zero();
};

/// The held step of the file comment for dt_s > 0 (std::invalid_argument otherwise, naming it).
HeldPrediction held_prediction(const Vec12& x, double dt_s, const ConstantVelocityOptions& noise,
                               double lost_attitude_sigma_rad, double lost_rate_sigma_radps);

}  // namespace nav::core

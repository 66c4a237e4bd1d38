#pragma once
// Constant-velocity process model of the robot state (Eustice et al., RSS 2005, section 4.1;
// Fossen 2011 kinematics). State order: core/README.md / geometry/types.h.
//
// Continuous model:   d/dt [pose] = f_pose(x) = [R_world_body(rpy) v_body; J2(rpy) omega_body]
//                     d/dt [v_body; omega_body] = g(x) + w(t),  w white, PSD Qc =
//                     diag(accel_psd, angular_accel_psd).
//   g = 0 (random-walk velocities) except, with AttitudeRestoringOptions, the roll and pitch
//   rates of a passively stable vehicle, each a damped oscillator about its equilibrium
//   (Fossen 2011, ch. 4, hydrostatic restoring moments; period T, damping ratio zeta,
//   omega = 2 pi / T):
//     dp/dt = -omega_r^2 (roll - trim_r) - 2 zeta_r omega_r p
//     dq/dt = -omega_p^2 (pitch - trim_p - c w) - 2 zeta_p omega_p q     (c: pitch per heave)
// Discretisation (first order, Euler):   x_k+1 = x_k + dt f(x_k), angles wrapped;
//   F = I + dt df/dx (analytic).
// Process noise: Q = integral_0^dt Phi(tau) G Qc G^T Phi(tau)^T dtau with Phi(tau) = I + tau A,
//   A = df/dx, G = [0; I6]. With g = 0, A G = [B; 0] with B = blockdiag(R_world_body, J2), so
//     Q = [ dt^3/3 B Qc B^T   dt^2/2 B Qc ]
//         [ dt^2/2 Qc B^T     dt Qc       ]
//   i.e. velocity random walk Q_vel = Qc dt, propagated consistently into the pose block. The
//   restoring terms add O(dt^2 omega) to the velocity block; the same Q is used (first order).
// Singularity: J2 divides by cos(pitch); predict() and process_noise() throw
// std::domain_error when pitch_is_singular (rotation.h). Invalid dt (<= 0, NaN, Inf) throws
// std::invalid_argument.

#include "nav/core/geometry/types.h"
#include "nav/core/status.h"

namespace nav::core {

/// Roll and pitch as damped oscillators (file comment). A vehicle's values come from its logged
/// attitude and rates: regress dp/dt on (roll, p, 1) and dq/dt on (pitch, q, w, 1)
/// (docs/consistency.md "Roll and pitch restoring").
struct AttitudeRestoringOptions {
  /// Natural periods of roll and pitch, s; 0 leaves that rate a random walk. Finite, >= 0.
  Eigen::Vector2d natural_period_s = Eigen::Vector2d::Zero();
  /// Damping ratios zeta of roll and pitch, dimensionless. Finite, >= 0.
  Eigen::Vector2d damping_ratio = Eigen::Vector2d::Zero();
  /// Equilibrium roll and pitch at rest (static trim), rad. Finite.
  Eigen::Vector2d trim_rad = Eigen::Vector2d::Zero();
  /// Pitch equilibrium shift per body heave velocity w, rad per m/s (< 0: nose up climbing).
  double pitch_per_heave_rad_per_mps = 0.0;

  bool enabled() const { return (natural_period_s.array() > 0.0).any(); }
};

struct ConstantVelocityOptions {
  /// Power spectral density of the body-frame linear acceleration noise per axis [u v w],
  /// m^2/s^3. Velocity variance grows by accel_psd * dt. Must be finite and >= 0.
  Vec3 accel_psd = Vec3::Constant(1e-3);
  /// PSD of the body angular acceleration noise per axis [p q r], rad^2/s^3. Finite, >= 0.
  Vec3 angular_accel_psd = Vec3::Constant(1e-5);
  /// Off by default: roll and pitch rates are random walks like the others.
  AttitudeRestoringOptions attitude_restoring;

  /// kInvalidArgument naming the field when an entry is negative or not finite.
  Status validate() const;
};

class ConstantVelocityModel {
 public:
  /// Throws std::invalid_argument with validate()'s message when options are invalid.
  explicit ConstantVelocityModel(const ConstantVelocityOptions& options = {});

  const ConstantVelocityOptions& options() const { return options_; }

  /// x(t + dt) = x + dt f(x) (angles wrapped); F = d predict / d x if requested.
  /// With attitude restoring, dt should stay well below the shortest period / (2 pi).
  Vec12 predict(const Vec12& x, double dt_s, Mat12* F = nullptr) const;

  /// Discrete process noise Q(x, dt) (see file comment), symmetric positive semi-definite.
  Mat12 process_noise(const Vec12& x, double dt_s) const;

 private:
  ConstantVelocityOptions options_;
};

}  // namespace nav::core

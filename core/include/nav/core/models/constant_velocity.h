#pragma once
// Constant-velocity process model of the robot state (Eustice et al., RSS 2005, section 4.1;
// Fossen 2011 kinematics). State order: core/README.md / geometry/types.h.
//
// Continuous model:   d/dt [pose] = f_pose(x) = [R_world_body(rpy) v_body; J2(rpy) omega_body]
//                     d/dt [v_body; omega_body] = w(t),  w white, PSD Qc = diag(accel_psd,
//                     angular_accel_psd)  (random-walk velocities).
// Discretisation (first order, Euler):   x_k+1 = x_k + dt f(x_k), angles wrapped,
//   velocities unchanged;  F = I + dt df/dx (analytic).
// Process noise: Q = integral_0^dt Phi(tau) G Qc G^T Phi(tau)^T dtau with Phi(tau) = I + tau A,
//   A = df/dx, G = [0; I6]. Since A G = [B; 0] with B = blockdiag(R_world_body, J2),
//     Q = [ dt^3/3 B Qc B^T   dt^2/2 B Qc ]
//         [ dt^2/2 Qc B^T     dt Qc       ]
//   i.e. velocity random walk Q_vel = Qc dt, propagated consistently into the pose block.
// Singularity: J2 divides by cos(pitch); predict() and process_noise() throw
// std::domain_error when pitch_is_singular (rotation.h). Invalid dt (<= 0, NaN, Inf) throws
// std::invalid_argument.

#include "nav/core/geometry/types.h"
#include "nav/core/status.h"

namespace nav::core {

struct ConstantVelocityOptions {
  /// Power spectral density of the body-frame linear acceleration noise per axis [u v w],
  /// m^2/s^3. Velocity variance grows by accel_psd * dt. Must be finite and >= 0.
  Vec3 accel_psd = Vec3::Constant(1e-3);
  /// PSD of the body angular acceleration noise per axis [p q r], rad^2/s^3. Finite, >= 0.
  Vec3 angular_accel_psd = Vec3::Constant(1e-5);

  /// kInvalidArgument naming the field when an entry is negative or not finite.
  Status validate() const;
};

class ConstantVelocityModel {
 public:
  /// Throws std::invalid_argument with validate()'s message when options are invalid.
  explicit ConstantVelocityModel(const ConstantVelocityOptions& options = {});

  const ConstantVelocityOptions& options() const { return options_; }

  /// x(t + dt) = x + dt f(x) (angles wrapped); F = d predict / d x if requested.
  Vec12 predict(const Vec12& x, double dt_s, Mat12* F = nullptr) const;

  /// Discrete process noise Q(x, dt) (see file comment), symmetric positive semi-definite.
  Mat12 process_noise(const Vec12& x, double dt_s) const;

 private:
  ConstantVelocityOptions options_;
};

}  // namespace nav::core

#pragma once
// Rotations from Z-Y-X Euler angles and their derivatives (core/README.md "Frames").
//
// Convention (Fossen 2011, Smith, Self & Cheeseman 1990):
//   rpy = [roll pitch heading] = [phi theta psi], radians,
//   R_world_body = Rz(psi) * Ry(theta) * Rx(phi) takes body vectors to world.
// Body angular rate omega_body is defined by R^T dR/dt = [omega_body]x, and
//   d(rpy)/dt = J2(rpy) * omega_body            (euler_rate_matrix),
//   omega_body = J2^-1(rpy) * d(rpy)/dt           (euler_rate_matrix_inverse, never singular).
//
// Singularity policy: J2 divides by cos(pitch). Every function in nav_core that divides by
// cos(pitch) (here: euler_rate_matrix and its derivatives; elsewhere: the pose Jacobians and
// the constant-velocity model) throws std::domain_error naming the offending pitch when
// pitch_is_singular(pitch), i.e. |pitch| > kMaxAbsPitchRad. They never return NaN. Callers on
// the real-time path check pitch_is_singular() first and report StatusCode::kOutOfRange.

#include <numbers>

#include "nav/core/geometry/types.h"

namespace nav::core {

/// Largest |pitch| (rad) at which Euler-rate quantities are computed: 89.5 deg.
/// Beyond it 1/cos(pitch) > 114 and the Euler parametrisation is numerically meaningless.
inline constexpr double kMaxAbsPitchRad = 89.5 * std::numbers::pi / 180.0;

/// True when |pitch| > kMaxAbsPitchRad or pitch is not finite.
bool pitch_is_singular(double pitch_rad);

/// Throws std::domain_error("<where>: pitch ... rad is within 0.5 deg of +-90 deg ...") when
/// pitch_is_singular(pitch_rad). `where` names the calling function for the message.
void require_regular_pitch(double pitch_rad, const char* where);

/// Wraps an angle to (-pi, pi]. Exactly pi stays pi; -pi maps to pi. NaN stays NaN.
double wrap_angle(double a_rad);

/// Elementary rotations (right-handed, active): rot_x(a) rotates vectors about +x by a.
Mat3 rot_x(double a_rad);
Mat3 rot_y(double a_rad);
Mat3 rot_z(double a_rad);

/// R_world_body = Rz(heading) Ry(pitch) Rx(roll).
Mat3 rotation_from_euler(const Vec3& rpy);

/// Inverse of rotation_from_euler: [roll pitch heading] with roll, heading in (-pi, pi] and
/// pitch in [-pi/2, pi/2]. At pitch = +-90 deg (gimbal lock) roll and heading are not
/// separable; the result is still finite (atan2 of the remaining entries), never NaN.
Vec3 euler_from_rotation(const Mat3& R_world_body);

/// Partial derivatives of rotation_from_euler(rpy) with respect to each angle:
///   dR/droll = R [e_x]x,  dR/dpitch = Rz Ry [e_y]x Rx,  dR/dheading = [e_z]x R.
Mat3 dR_droll(const Vec3& rpy);
Mat3 dR_dpitch(const Vec3& rpy);
Mat3 dR_dheading(const Vec3& rpy);

/// J2 of Fossen: d(rpy)/dt = J2(rpy) omega_body.
///   [1  sin(phi)tan(theta)  cos(phi)tan(theta)]
///   [0  cos(phi)            -sin(phi)         ]
///   [0  sin(phi)/cos(theta) cos(phi)/cos(theta)]
/// Throws std::domain_error when pitch_is_singular(rpy[1]).
Mat3 euler_rate_matrix(const Vec3& rpy);

/// J2^-1: omega_body = J2^-1(rpy) d(rpy)/dt. Defined for every rpy (no division).
Mat3 euler_rate_matrix_inverse(const Vec3& rpy);

/// dJ2/droll and dJ2/dpitch (J2 does not depend on heading). Throw like euler_rate_matrix.
Mat3 dJ2_droll(const Vec3& rpy);
Mat3 dJ2_dpitch(const Vec3& rpy);

/// Skew-symmetric cross-product matrix: skew(a) b = a x b.
Mat3 skew(const Vec3& a);

}  // namespace nav::core

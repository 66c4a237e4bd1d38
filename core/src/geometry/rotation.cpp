// Z-Y-X Euler rotations, Euler-rate matrix J2 and derivatives (rotation.h; Fossen 2011,
// section 2.2).

#include "nav/core/geometry/rotation.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace nav::core {

bool pitch_is_singular(double pitch_rad) {
  return !std::isfinite(pitch_rad) || std::abs(pitch_rad) > kMaxAbsPitchRad;
}

void require_regular_pitch(double pitch_rad, const char* where) {
  if (!pitch_is_singular(pitch_rad)) return;
  std::ostringstream msg;
  msg << std::setprecision(10) << where << ": pitch " << pitch_rad << " rad ("
      << pitch_rad * 180.0 / std::numbers::pi << " deg) is beyond +-"
      << kMaxAbsPitchRad * 180.0 / std::numbers::pi
      << " deg, where the Euler-angle rate matrix is singular";
  throw std::domain_error(msg.str());
}

double wrap_angle(double a_rad) {
  constexpr double kPi = std::numbers::pi;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  if (a_rad > -kPi && a_rad <= kPi) return a_rad;
  double r = std::fmod(a_rad + kPi, kTwoPi);  // in (-2pi, 2pi)
  if (r <= 0.0) r += kTwoPi;                  // in (0, 2pi]
  return r - kPi;                             // in (-pi, pi]
}

Mat3 rot_x(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Mat3 R;
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

Mat3 rot_y(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Mat3 R;
  R << c, 0, s, 0, 1, 0, -s, 0, c;
  return R;
}

Mat3 rot_z(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Mat3 R;
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

Mat3 rotation_from_euler(const Vec3& rpy) { return rot_z(rpy[2]) * rot_y(rpy[1]) * rot_x(rpy[0]); }

Vec3 euler_from_rotation(const Mat3& R) {
  // R(2,0) = -sin(pitch); clamp guards |R(2,0)| slightly above 1 from rounding.
  const double s_pitch = std::clamp(-R(2, 0), -1.0, 1.0);
  return {std::atan2(R(2, 1), R(2, 2)), std::asin(s_pitch), std::atan2(R(1, 0), R(0, 0))};
}

Mat3 skew(const Vec3& a) {
  Mat3 S;
  S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return S;
}

Mat3 dR_droll(const Vec3& rpy) { return rotation_from_euler(rpy) * skew(Vec3::UnitX()); }

Mat3 dR_dpitch(const Vec3& rpy) {
  return rot_z(rpy[2]) * rot_y(rpy[1]) * skew(Vec3::UnitY()) * rot_x(rpy[0]);
}

Mat3 dR_dheading(const Vec3& rpy) { return skew(Vec3::UnitZ()) * rotation_from_euler(rpy); }

Mat3 euler_rate_matrix(const Vec3& rpy) {
  require_regular_pitch(rpy[1], "euler_rate_matrix");
  const double sr = std::sin(rpy[0]), cr = std::cos(rpy[0]);
  const double cp = std::cos(rpy[1]), tp = std::tan(rpy[1]);
  Mat3 J;
  J << 1, sr * tp, cr * tp, 0, cr, -sr, 0, sr / cp, cr / cp;
  return J;
}

Mat3 euler_rate_matrix_inverse(const Vec3& rpy) {
  const double sr = std::sin(rpy[0]), cr = std::cos(rpy[0]);
  const double sp = std::sin(rpy[1]), cp = std::cos(rpy[1]);
  Mat3 E;
  E << 1, 0, -sp, 0, cr, sr * cp, 0, -sr, cr * cp;
  return E;
}

Mat3 dJ2_droll(const Vec3& rpy) {
  require_regular_pitch(rpy[1], "dJ2_droll");
  const double sr = std::sin(rpy[0]), cr = std::cos(rpy[0]);
  const double cp = std::cos(rpy[1]), tp = std::tan(rpy[1]);
  Mat3 D;
  D << 0, cr * tp, -sr * tp, 0, -sr, -cr, 0, cr / cp, -sr / cp;
  return D;
}

Mat3 dJ2_dpitch(const Vec3& rpy) {
  require_regular_pitch(rpy[1], "dJ2_dpitch");
  const double sr = std::sin(rpy[0]), cr = std::cos(rpy[0]);
  const double cp = std::cos(rpy[1]), tp = std::tan(rpy[1]);
  const double sec2 = 1.0 / (cp * cp);
  Mat3 D;
  // d tan/dp = sec^2, d sec/dp = sec tan.
  D << 0, sr * sec2, cr * sec2, 0, 0, 0, 0, sr * tp / cp, cr * tp / cp;
  return D;
}

}  // namespace nav::core

#pragma once
// Hand-written and random poses and robot states for the geometry and model tests (fixed seeds),
// and the numeric-Jacobian adaptors with angle-wrapped differences. Test-only.

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/geometry/types.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::core::test {

inline constexpr double kPi = std::numbers::pi;
inline double deg(double d) { return d * kPi / 180.0; }

/// Pose [x y z roll pitch heading] (m, rad) from its six components, for hand-written cases.
inline Vec6 pose(double x, double y, double z, double r, double p, double h) {
  Vec6 v;
  v << x, y, z, r, p, h;
  return v;
}

/// Random pose: position in [-10, 10] m, roll and heading in (-pi, pi], |pitch| <= 80 deg.
inline Vec6 random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> pos(-10.0, 10.0), ang(-kPi, kPi), pitch(-deg(80), deg(80));
  Vec6 x;
  x << pos(rng), pos(rng), pos(rng), ang(rng), pitch(rng), ang(rng);
  return x;
}

/// Random robot state: random_pose plus velocities in [-2, 2] m/s and rates in [-0.5, 0.5] rad/s.
inline Vec12 random_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> vel(-2.0, 2.0), rate(-0.5, 0.5);
  Vec12 x;
  x.head<6>() = random_pose(rng);
  x.segment<3>(kU) << vel(rng), vel(rng), vel(rng);
  x.segment<3>(kP) << rate(rng), rate(rng), rate(rng);
  return x;
}

/// Element-wise difference with every `angle_rows` entry wrapped.
inline Eigen::VectorXd wrapped_minus(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                                     const std::vector<int>& angle_rows) {
  Eigen::VectorXd d = a - b;
  for (int r : angle_rows) d[r] = wrap_angle(d[r]);
  return d;
}

/// Pose difference (angles 3..5 wrapped) for numeric_jacobian of pose-valued functions.
inline Eigen::VectorXd pose_diff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return wrapped_minus(a, b, {3, 4, 5});
}

}  // namespace nav::core::test

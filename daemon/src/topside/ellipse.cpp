// Closed-form 2x2 eigen-decomposition; Eigen's SelfAdjointEigenSolver for the 3x3 ellipsoid.
#include "nav/daemon/topside/ellipse.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace nav::daemon::topside {

Ellipse2 covariance_ellipse(double pxx_m2, double pxy_m2, double pyy_m2, double k_sigma) {
  // Eigenvalues of a symmetric 2x2: mean +- sqrt(((a-d)/2)^2 + b^2); the major axis angle
  // theta solves tan(2 theta) = 2 b / (a - d).
  const double mean = 0.5 * (pxx_m2 + pyy_m2);
  const double half_diff = 0.5 * (pxx_m2 - pyy_m2);
  const double radius = std::hypot(half_diff, pxy_m2);
  const double l1 = std::max(mean + radius, 0.0);
  const double l2 = std::max(mean - radius, 0.0);
  Ellipse2 e;
  e.semi_major_m = k_sigma * std::sqrt(l1);
  e.semi_minor_m = k_sigma * std::sqrt(l2);
  e.angle_rad = 0.5 * std::atan2(2.0 * pxy_m2, pxx_m2 - pyy_m2);
  return e;
}

Ellipsoid3 covariance_ellipsoid(const std::array<double, 9>& p_m2, double k_sigma) {
  const Eigen::Matrix3d P = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(p_m2.data());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (P + P.transpose()));
  Eigen::Matrix3d R = eig.eigenvectors();
  if (R.determinant() < 0.0) R.col(2) = -R.col(2);  // a proper rotation
  Ellipsoid3 out;
  for (int i = 0; i < 3; ++i) {
    out.size_m[i] = 2.0 * k_sigma * std::sqrt(std::max(eig.eigenvalues()[i], 0.0));
  }
  const Eigen::Quaterniond q(R);
  out.q_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return out;
}

std::array<double, 9> position_block(const double* cov6x6) {
  std::array<double, 9> p{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p[3 * r + c] = cov6x6[6 * r + c];
  }
  return p;
}

}  // namespace nav::daemon::topside

// z <-> relative pose conversions of the 5-DOF camera measurement (relative_pose_5dof.h).
// The Jacobian of z with respect to t is the one of nav::core::CameraRelativePoseModel
// (binary_models.cpp); both are tested against numeric differences.

#include "nav/vision/relative_pose_5dof.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"

namespace nav::vision {

Eigen::Vector3d baseline_direction(double azimuth_rad, double elevation_rad, Mat3x2* J) {
  const double ca = std::cos(azimuth_rad), sa = std::sin(azimuth_rad);
  const double ce = std::cos(elevation_rad), se = std::sin(elevation_rad);
  if (J != nullptr) {
    *J << -ce * sa, -se * ca,  //
        ce * ca, -se * sa,     //
        0.0, ce;
  }
  return {ce * ca, ce * sa, se};
}

Vec5 z_from_relative_pose(const Vec6& x_i_j, Mat5x6* J) {
  const double tx = x_i_j[0], ty = x_i_j[1], tz = x_i_j[2];
  const double rho2 = tx * tx + ty * ty;
  const double rho = std::sqrt(rho2);
  const double norm = std::sqrt(rho2 + tz * tz);
  if (!(rho > kMinHorizontalBaseline * norm) || !(norm > 0.0)) {
    std::ostringstream msg;
    msg << "z_from_relative_pose: baseline t_i_j = [" << tx << ", " << ty << ", " << tz
        << "] has no defined azimuth (|[t_x t_y]| = " << rho << ")";
    throw std::domain_error(msg.str());
  }
  Vec5 z;
  z << std::atan2(ty, tx), std::atan2(tz, rho), core::wrap_angle(x_i_j[3]),
      core::wrap_angle(x_i_j[4]), core::wrap_angle(x_i_j[5]);
  if (J != nullptr) {
    const double r2 = rho2 + tz * tz;
    J->setZero();
    (*J)(0, 0) = -ty / rho2;
    (*J)(0, 1) = tx / rho2;
    (*J)(1, 0) = -tx * tz / (rho * r2);
    (*J)(1, 1) = -ty * tz / (rho * r2);
    (*J)(1, 2) = rho / r2;
    J->bottomRightCorner<3, 3>().setIdentity();
  }
  return z;
}

Vec5 z_from_rotation_translation(const Eigen::Matrix3d& R_i_j, const Eigen::Vector3d& t_i_j) {
  Vec6 x;
  x << t_i_j, core::euler_from_rotation(R_i_j);
  return z_from_relative_pose(x);
}

Vec6 relative_pose_from_z(const Vec5& z, double baseline_m, Mat6x5* J) {
  Mat3x2 J_t;
  const Eigen::Vector3d t_unit = baseline_direction(z[0], z[1], J != nullptr ? &J_t : nullptr);
  Vec6 x;
  x << baseline_m * t_unit, z.tail<3>();
  if (J != nullptr) {
    J->setZero();
    J->topLeftCorner<3, 2>() = baseline_m * J_t;
    J->bottomRightCorner<3, 3>().setIdentity();
  }
  return x;
}

Eigen::Matrix3d rotation_from_z(const Vec5& z) {
  return core::rotation_from_euler(Eigen::Vector3d(z[2], z[3], z[4]));
}

Vec5 z_minus(const Vec5& a, const Vec5& b) {
  Vec5 d;
  for (int k = 0; k < 5; ++k) d[k] = core::wrap_angle(a[k] - b[k]);
  return d;
}

PredictedZ predict_z(const RelativePosePrior& prior) {
  Mat5x6 J;
  PredictedZ out;
  out.z = z_from_relative_pose(prior.x_i_j, &J);
  out.covariance = J * prior.covariance * J.transpose();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  return out;
}

double z_chi2(const Vec5& z, const Mat5& z_covariance, const PredictedZ& predicted) {
  const Mat5 S = z_covariance + predicted.covariance;
  const Eigen::LLT<Mat5> llt(S);
  if (llt.info() != Eigen::Success || !S.allFinite()) {
    std::ostringstream msg;
    msg << "z_chi2: innovation covariance (measurement + prediction) is not positive definite; "
           "diagonal = ["
        << S.diagonal().transpose() << "]";
    throw std::invalid_argument(msg.str());
  }
  const Vec5 nu = z_minus(z, predicted.z);
  return nu.dot(llt.solve(nu));
}

}  // namespace nav::vision

#pragma once
// Conversions between the 5-DOF camera measurement and a relative pose, with Jacobians.
//
// The measurement is exactly nav::core::CameraRelativePoseModel's (binary_models.h):
//   z = [azimuth, elevation, roll, pitch, heading] of camera j in camera i, where for the
//   relative pose x_i_j = [t_i_j; roll pitch heading] (p_i = R_i_j p_j + t_i_j,
//   R_i_j = Rz(heading) Ry(pitch) Rx(roll)):
//     azimuth   = atan2(t_y, t_x)                  in (-pi, pi],
//     elevation = atan2(t_z, sqrt(t_x^2 + t_y^2))  in [-pi/2, pi/2].
// Scale is unobservable from two monocular views, so z keeps only the baseline direction
//   t_unit(azimuth, elevation) = [cos(el) cos(az), cos(el) sin(az), sin(el)].
// Eustice, Singh, Leonard, Walter & Ballard, RSS 2005, section III-C.
//
// Singularities: the azimuth is undefined when sqrt(t_x^2 + t_y^2) is zero (baseline along the
// optical axis, or no baseline). Functions that need the azimuth throw std::domain_error
// naming the baseline when sqrt(t_x^2 + t_y^2) < kMinHorizontalBaseline (relative to |t|).
#include <Eigen/Core>

#include "nav/vision/vision_types.h"

namespace nav::vision {

using Mat5x6 = Eigen::Matrix<double, 5, 6>;
using Mat6x5 = Eigen::Matrix<double, 6, 5>;
using Mat3x2 = Eigen::Matrix<double, 3, 2>;

/// Smallest |[t_x t_y]| / |t| at which the azimuth is treated as defined.
inline constexpr double kMinHorizontalBaseline = 1e-9;

/// Unit baseline direction for (azimuth, elevation); J (optional) = d t_unit / d(az, el).
Eigen::Vector3d baseline_direction(double azimuth_rad, double elevation_rad, Mat3x2* J = nullptr);

/// z of the relative pose x_i_j = [t; rpy] (|t| arbitrary, not zero); angles wrapped to
/// (-pi, pi]. J (optional) = dz / dx_i_j (5x6): the azimuth/elevation rows depend on t only,
/// the angle rows are the identity on rpy. Throws std::domain_error when the azimuth is
/// undefined (see above).
Vec5 z_from_relative_pose(const Vec6& x_i_j, Mat5x6* J = nullptr);

/// z of a rotation and a baseline (any length, not zero). Throws like z_from_relative_pose.
Vec5 z_from_rotation_translation(const Eigen::Matrix3d& R_i_j, const Eigen::Vector3d& t_i_j);

/// Relative pose with baseline length `baseline_m` for z: [baseline_m * t_unit; z(2..4)].
/// J (optional) = d x_i_j / dz (6x5) at fixed baseline length.
Vec6 relative_pose_from_z(const Vec5& z, double baseline_m, Mat6x5* J = nullptr);

/// R_i_j = Rz(z[4]) Ry(z[3]) Rx(z[2]).
Eigen::Matrix3d rotation_from_z(const Vec5& z);

/// a - b with every component wrapped to (-pi, pi] (all five are angles).
Vec5 z_minus(const Vec5& a, const Vec5& b);

/// The prior's prediction of z and its 5x5 covariance, first order:
///   z_prior = z_from_relative_pose(prior.x_i_j),  P_z = J P_x J^T.
/// Throws std::domain_error when the prior's baseline has no defined azimuth.
struct PredictedZ {
  Vec5 z = Vec5::Zero();
  Mat5 covariance = Mat5::Identity();
};
PredictedZ predict_z(const RelativePosePrior& prior);

/// Mahalanobis distance squared of z against the prediction, with the innovation of
/// z_minus() and the summed covariance P_pred + R_meas (Cholesky solve). Distributed
/// chi2(5) when both are consistent. Throws std::invalid_argument when the sum is not positive
/// definite.
double z_chi2(const Vec5& z, const Mat5& z_covariance, const PredictedZ& predicted);

}  // namespace nav::vision

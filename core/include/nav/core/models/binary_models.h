#pragma once
// Binary (relative-pose) measurement models between two state blocks a and b, e.g. two
// delayed states of the ESDF (Eustice et al., RSS 2005, section on camera constraints).
// Common interface: measurement.h. Only the pose part (first 6 elements) of each block is
// used; Jacobian columns of velocity parts are zero.

#include "nav/core/geometry/types.h"
#include "nav/core/models/measurement.h"

namespace nav::core {

/// Full 6-DOF relative pose z = tail_to_tail(pose_a, pose_b) = x_ab, 6 rows
/// [x y z roll pitch heading] of b in a's body frame; rows 3..5 are angles.
/// Jacobians divide by cos(pitch of x_ab): they throw std::domain_error at the singularity
/// (rotation.h policy).
struct RelativePose6Model {
  int dim() const { return 6; }
  bool is_angle(int row) const { return row >= 3; }
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                  const Eigen::Ref<const Eigen::VectorXd>& x_b, MeasJac* H_a = nullptr,
                  MeasJac* H_b = nullptr) const;
};

/// 5-DOF camera relative pose of Eustice et al. (RSS 2005): scale is unobservable from
/// monocular images, so the baseline is measured only in direction.
/// With x_c = head_to_tail(pose, x_body_camera) the camera pose of each state and
/// x_ab = tail_to_tail(x_c_a, x_c_b) = [t_ab; rpy_ab] (camera b in camera a's frame,
/// camera frame: x right, y down, z optical axis), the measurement is (5 rows, all angles)
///   z = [azimuth, elevation, roll_ab, pitch_ab, heading_ab],
///   azimuth   = atan2(t_y, t_x)                       in (-pi, pi],
///   elevation = atan2(t_z, sqrt(t_x^2 + t_y^2))        in [-pi/2, pi/2].
/// Degenerate baseline: if sqrt(t_x^2 + t_y^2) < min_baseline_m the azimuth is undefined and
/// predict() throws std::domain_error naming the baseline; callers test
/// baseline_is_degenerate() first and skip the update (StatusCode::kOutOfRange).
struct CameraRelativePoseModel {
  Vec6 x_body_camera = Vec6::Zero();  ///< Camera mount pose in the body frame (SSC pose).
  double min_baseline_m = 1e-6;       ///< Smallest usable |[t_x t_y]| of the baseline, m.

  int dim() const { return 5; }
  bool is_angle(int /*row*/) const { return true; }
  /// Relative camera pose x_ab for the two states (no Jacobian).
  Vec6 camera_relative_pose(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                            const Eigen::Ref<const Eigen::VectorXd>& x_b) const;
  /// True when the azimuth of the baseline between the two states is undefined.
  bool baseline_is_degenerate(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                              const Eigen::Ref<const Eigen::VectorXd>& x_b) const;
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                  const Eigen::Ref<const Eigen::VectorXd>& x_b, MeasJac* H_a = nullptr,
                  MeasJac* H_b = nullptr) const;
};

}  // namespace nav::core

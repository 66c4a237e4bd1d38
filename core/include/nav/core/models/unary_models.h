#pragma once
// Unary measurement models: one state block (measurement.h for the common interface).
// Frames and state order: core/README.md. Each predict() has an analytic Jacobian.

#include "nav/core/geometry/types.h"
#include "nav/core/models/measurement.h"

namespace nav::core {

/// Doppler velocity log bottom-track velocity in the DVL frame (m/s, 3 rows, no angles):
///   v_dvl = R_body_dvl^T (v_body + omega_body x p_body_dvl_m).
/// Needs a 12-element robot state (velocities); depends only on [u v w p q r].
struct DvlVelocityModel {
  Mat3 R_body_dvl = Mat3::Identity();  ///< DVL axes expressed in body axes.
  Vec3 p_body_dvl_m = Vec3::Zero();    ///< DVL origin in body frame (lever arm), m.

  int dim() const { return 3; }
  bool is_angle(int /*row*/) const { return false; }
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H = nullptr) const;
};

/// Heading (compass / gyro heading), 1 row, angle: z = heading.
struct HeadingModel {
  int dim() const { return 1; }
  bool is_angle(int /*row*/) const { return true; }
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H = nullptr) const;
};

/// Roll and pitch (inclinometer / AHRS), 2 rows, angles: z = [roll pitch].
struct AttitudeModel {
  int dim() const { return 2; }
  bool is_angle(int /*row*/) const { return true; }
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H = nullptr) const;
};

/// Depth of the pressure sensor (m, positive down, 1 row):
///   z = z_world + (R_world_body p_body_sensor_m)_z.
struct DepthModel {
  Vec3 p_body_sensor_m = Vec3::Zero();  ///< Pressure sensor position in the body frame, m.

  int dim() const { return 1; }
  bool is_angle(int /*row*/) const { return false; }
  MeasVec predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H = nullptr) const;
};

}  // namespace nav::core

// Unary measurement models with analytic Jacobians (unary_models.h).

#include "nav/core/models/unary_models.h"

#include <Eigen/Geometry>

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {

/// Sizes H to dim x block and zeroes it.
void reset_jacobian(MeasJac* H, int dim, Eigen::Index block) {
  if (H != nullptr) H->setZero(dim, block);
}

}  // namespace

MeasVec DvlVelocityModel::predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H) const {
  require_block_size(x.size(), /*need_velocity=*/true, "DvlVelocityModel");
  const Vec3 v_body = x.segment<3>(kU);
  const Vec3 omega_body = x.segment<3>(kP);
  const Mat3 R_dvl_body = R_body_dvl.transpose();
  MeasVec z = R_dvl_body * (v_body + omega_body.cross(p_body_dvl_m));
  if (H != nullptr) {
    reset_jacobian(H, 3, x.size());
    H->block<3, 3>(0, kU) = R_dvl_body;
    // omega x p = -p x omega = -[p]x omega.
    H->block<3, 3>(0, kP) = -R_dvl_body * skew(p_body_dvl_m);
  }
  return z;
}

MeasVec HeadingModel::predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H) const {
  require_block_size(x.size(), false, "HeadingModel");
  MeasVec z(1);
  z[0] = x[kHeading];
  if (H != nullptr) {
    reset_jacobian(H, 1, x.size());
    (*H)(0, kHeading) = 1.0;
  }
  return z;
}

MeasVec AttitudeModel::predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H) const {
  require_block_size(x.size(), false, "AttitudeModel");
  MeasVec z(2);
  z << x[kRoll], x[kPitch];
  if (H != nullptr) {
    reset_jacobian(H, 2, x.size());
    (*H)(0, kRoll) = 1.0;
    (*H)(1, kPitch) = 1.0;
  }
  return z;
}

MeasVec DepthModel::predict(const Eigen::Ref<const Eigen::VectorXd>& x, MeasJac* H) const {
  require_block_size(x.size(), false, "DepthModel");
  const Vec3 rpy = x.segment<3>(kRoll);
  MeasVec z(1);
  z[0] = x[kZ] + rotation_from_euler(rpy).row(2).dot(p_body_sensor_m);
  if (H != nullptr) {
    reset_jacobian(H, 1, x.size());
    (*H)(0, kZ) = 1.0;
    (*H)(0, kRoll) = dR_droll(rpy).row(2).dot(p_body_sensor_m);
    (*H)(0, kPitch) = dR_dpitch(rpy).row(2).dot(p_body_sensor_m);
    (*H)(0, kHeading) = dR_dheading(rpy).row(2).dot(p_body_sensor_m);
  }
  return z;
}

}  // namespace nav::core

// Smith-Self-Cheeseman compounding with closed-form Jacobians (pose.h).
//
// Angle rows: with omega = (R^T dR)^vee the body-frame perturbation of a rotation and
// E(rpy) = J2^-1(rpy), a change d(rpy_in) of an input's angles perturbs the input rotation by
// omega_in = E(rpy_in) d(rpy_in); the output rotation's body perturbation is a fixed rotation
// of omega_in, and d(rpy_out) = J2(rpy_out) omega_out.

#include "nav/core/geometry/pose.h"

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {

Vec3 angles(const Vec6& x) { return x.tail<3>(); }

Vec6 make_pose(const Vec3& t, const Mat3& R) {
  Vec6 out;
  out.head<3>() = t;
  out.tail<3>() = euler_from_rotation(R);
  return out;
}

/// [dR/droll v, dR/dpitch v, dR/dheading v] for R = R(rpy).
Mat3 dRv_drpy(const Vec3& rpy, const Vec3& v) {
  Mat3 D;
  D.col(0) = dR_droll(rpy) * v;
  D.col(1) = dR_dpitch(rpy) * v;
  D.col(2) = dR_dheading(rpy) * v;
  return D;
}

/// [dR^T/droll v, dR^T/dpitch v, dR^T/dheading v].
Mat3 dRtv_drpy(const Vec3& rpy, const Vec3& v) {
  Mat3 D;
  D.col(0) = dR_droll(rpy).transpose() * v;
  D.col(1) = dR_dpitch(rpy).transpose() * v;
  D.col(2) = dR_dheading(rpy).transpose() * v;
  return D;
}

}  // namespace

Mat3 pose_rotation(const Vec6& x) { return rotation_from_euler(angles(x)); }

Vec3 pose_translation(const Vec6& x) { return x.head<3>(); }

Vec6 head_to_tail(const Vec6& x_ij, const Vec6& x_jk, Mat6x12* J) {
  const Mat3 R_ij = pose_rotation(x_ij);
  const Mat3 R_jk = pose_rotation(x_jk);
  const Vec3 t_jk = pose_translation(x_jk);
  const Vec6 x_ik = make_pose(pose_translation(x_ij) + R_ij * t_jk, R_ij * R_jk);
  if (J != nullptr) {
    require_regular_pitch(x_ik[kPitch], "head_to_tail Jacobian (pitch of x_ik)");
    const Mat3 J2_ik = euler_rate_matrix(angles(x_ik));
    J->setZero();
    J->block<3, 3>(0, 0).setIdentity();
    J->block<3, 3>(0, 3) = dRv_drpy(angles(x_ij), t_jk);
    J->block<3, 3>(3, 3) = J2_ik * R_jk.transpose() * euler_rate_matrix_inverse(angles(x_ij));
    J->block<3, 3>(0, 6) = R_ij;
    J->block<3, 3>(3, 9) = J2_ik * euler_rate_matrix_inverse(angles(x_jk));
  }
  return x_ik;
}

Vec6 inverse_pose(const Vec6& x_ij, Mat6* J) {
  const Mat3 R_ij = pose_rotation(x_ij);
  const Vec3 t_ij = pose_translation(x_ij);
  const Vec6 x_ji = make_pose(-R_ij.transpose() * t_ij, R_ij.transpose());
  if (J != nullptr) {
    require_regular_pitch(x_ji[kPitch], "inverse_pose Jacobian (pitch of x_ji)");
    J->setZero();
    J->block<3, 3>(0, 0) = -R_ij.transpose();
    J->block<3, 3>(0, 3) = -dRtv_drpy(angles(x_ij), t_ij);
    // R_ji^T dR_ji = -[R_ij omega_ij]x.
    J->block<3, 3>(3, 3) =
        -euler_rate_matrix(angles(x_ji)) * R_ij * euler_rate_matrix_inverse(angles(x_ij));
  }
  return x_ji;
}

Vec6 tail_to_tail(const Vec6& x_ij, const Vec6& x_ik, Mat6x12* J) {
  const Mat3 R_ij = pose_rotation(x_ij);
  const Vec3 d_i = pose_translation(x_ik) - pose_translation(x_ij);
  const Mat3 R_jk = R_ij.transpose() * pose_rotation(x_ik);
  const Vec6 x_jk = make_pose(R_ij.transpose() * d_i, R_jk);
  if (J != nullptr) {
    require_regular_pitch(x_jk[kPitch], "tail_to_tail Jacobian (pitch of x_jk)");
    const Mat3 J2_jk = euler_rate_matrix(angles(x_jk));
    J->setZero();
    J->block<3, 3>(0, 0) = -R_ij.transpose();
    J->block<3, 3>(0, 3) = dRtv_drpy(angles(x_ij), d_i);
    // dR_jk = dR_ij^T R_ik  =>  R_jk^T dR_jk = -[R_jk^T omega_ij]x.
    J->block<3, 3>(3, 3) = -J2_jk * R_jk.transpose() * euler_rate_matrix_inverse(angles(x_ij));
    J->block<3, 3>(0, 6) = R_ij.transpose();
    J->block<3, 3>(3, 9) = J2_jk * euler_rate_matrix_inverse(angles(x_ik));
  }
  return x_jk;
}

Vec6 pose_minus(const Vec6& a, const Vec6& b) {
  Vec6 d = a - b;
  for (int k = kRoll; k <= kHeading; ++k) d[k] = wrap_angle(d[k]);
  return d;
}

}  // namespace nav::core

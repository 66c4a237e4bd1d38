#pragma once
// Smith-Self-Cheeseman 6-DOF pose algebra with analytic Jacobians.
// Smith, Self & Cheeseman, "Estimating uncertain spatial relationships in robotics" (1990);
// Eustice, PhD thesis (MIT/WHOI 2005), appendix on 6-DOF compounding.
//
// A pose x_ij = [x y z roll pitch heading] (Vec6) is frame j expressed in frame i:
// position t_ij of j's origin in i (metres) and Z-Y-X Euler angles of R_ij (rotation.h), so a
// point p_j in frame j is p_i = R_ij p_j + t_ij. Angles of every result are wrapped to (-pi, pi].
//
// Jacobians are optional outputs (nullptr = not computed), written in closed form. The angle
// rows are obtained from the body-frame perturbation of the result rotation,
//   d(rpy_out) = J2(rpy_out) * (R_out^T dR_out)^vee,
// which is algebraically equal to SSC's element-wise formulas. They divide by cos of the
// result's pitch: when a Jacobian is requested and that pitch is singular (rotation.h,
// pitch_is_singular) the function throws std::domain_error; the values alone never throw.

#include "nav/core/geometry/types.h"

namespace nav::core {

/// Head-to-tail compounding x_ik = x_ij (+) x_jk:
///   t_ik = t_ij + R_ij t_jk,  R_ik = R_ij R_jk.
/// J = [d x_ik / d x_ij | d x_ik / d x_jk] (6x12).
Vec6 head_to_tail(const Vec6& x_ij, const Vec6& x_jk, Mat6x12* J = nullptr);

/// Inverse x_ji = (-) x_ij:  t_ji = -R_ij^T t_ij,  R_ji = R_ij^T.  J = d x_ji / d x_ij.
Vec6 inverse_pose(const Vec6& x_ij, Mat6* J = nullptr);

/// Tail-to-tail x_jk = (-)x_ij (+) x_ik:  t_jk = R_ij^T (t_ik - t_ij),  R_jk = R_ij^T R_ik.
/// J = [d x_jk / d x_ij | d x_jk / d x_ik] (6x12).
Vec6 tail_to_tail(const Vec6& x_ij, const Vec6& x_ik, Mat6x12* J = nullptr);

/// a - b with the angle components (3..5) wrapped to (-pi, pi].
Vec6 pose_minus(const Vec6& a, const Vec6& b);

/// Rotation and translation of a pose (conveniences used by the models).
Mat3 pose_rotation(const Vec6& x);
Vec3 pose_translation(const Vec6& x);

}  // namespace nav::core

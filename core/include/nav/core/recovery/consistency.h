#pragma once
// Consistency metrics for covariance estimates (Eustice et al., RSS 2005, Sec. IV, Fig. 3):
// is a bound conservative (bound - exact PSD), the relative-pose covariance of two states
// from their joint, and the log-determinant ratio the paper plots.

#include <Eigen/Core>
#include <vector>

#include "nav/core/geometry/types.h"

namespace nav::core {

/// True when bound - exact is positive semi-definite within tolerance:
///   min eig(sym(bound - exact)) >= -tol * max(‖exact‖_2, tiny),
/// i.e. tol is relative to the spectral norm of `exact` (1e-9 is a good choice for exact
/// marginals from ExactMarginals; looser for iterative estimates). Checked by a pivoted LDLT
/// of (bound - exact + tol*‖exact‖ I): conservative iff every pivot of D is >= 0. `min_eig`
/// (optional) receives the smallest eigenvalue of sym(bound - exact) (self-adjoint solver),
/// for messages. Sizes must match and be square (std::invalid_argument otherwise).
bool is_conservative(const Eigen::MatrixXd& bound, const Eigen::MatrixXd& exact, double tol,
                     double* min_eig = nullptr);

/// First-order covariance of the relative pose x_ri = (-)x_r (+) x_i (geometry/pose.h
/// tail_to_tail) from the 12x12 joint covariance [[S_rr S_ri]; [S_ir S_ii]] of the two 6-DOF
/// poses and their means: J joint J^T with J the 6x12 tail_to_tail Jacobian at the means.
/// For 12-element robot states pass the pose rows/cols only (the first 6 of each).
Mat6 relative_pose_covariance(const Mat12& joint, const Vec6& x_r, const Vec6& x_i);

/// The pose rows/cols of a 2d x 2d joint of two d-element blocks [[S_rr S_ri]; [S_ir S_ii]]:
/// [0, 6) and [d, d + 6), the input of relative_pose_covariance(). Throws
/// std::invalid_argument unless the joint is square with an even size 2d, d >= 6.
Mat12 pose_joint(const Eigen::MatrixXd& joint);

/// log det(ours) - log det(exact) (paper Fig. 3): positive = ours is larger in volume
/// (conservative-looking), negative = over-confident. Any square size (Mat6 for poses); both
/// must be SPD (computed from LLT diagonals; throws std::invalid_argument otherwise or when the
/// sizes differ). One Ref signature, so Mat6, MatrixXd and blocks mix without ambiguity.
double logdet_ratio(const Eigen::Ref<const Eigen::MatrixXd>& ours,
                    const Eigen::Ref<const Eigen::MatrixXd>& exact);

/// min / median / max (median of an even count = mean of the two middle values) and count.
struct SummaryStats {
  double min = 0.0;
  double median = 0.0;
  double max = 0.0;
  size_t count = 0;
};
/// Throws std::invalid_argument for an empty vector.
SummaryStats summarize(std::vector<double> values);

}  // namespace nav::core

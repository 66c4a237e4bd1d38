// Link hypotheses from the bounds (navigation/link_proposer.h).
#include "nav/core/navigation/link_proposer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/pose.h"
#include "nav/core/recovery/consistency.h"

namespace nav::core {
namespace {

constexpr int kD = 12;  // block dimension

LinkProposerOptions validated(const LinkProposerOptions& o) {
  if (!(o.min_probability > 0.0 && o.min_probability < 1.0) ||
      !(o.min_overlap_fraction > 0.0 && o.min_overlap_fraction <= 1.0) || o.max_per_image < 1) {
    throw std::invalid_argument(
        "LinkProposer: min_probability must be in (0, 1) (is " + std::to_string(o.min_probability) +
        "), min_overlap_fraction in (0, 1] (is " + std::to_string(o.min_overlap_fraction) +
        "), max_per_image >= 1 (is " + std::to_string(o.max_per_image) + ")");
  }
  return o;
}

}  // namespace

LinkProposer::LinkProposer(const LinkProposerOptions& options,
                           const Eigen::Vector2d& half_extent_per_altitude,
                           const Vec6& x_body_camera)
    : options_(validated(options)),
      half_extent_per_altitude_(half_extent_per_altitude),
      x_body_camera_(x_body_camera),
      prefilter_chi2_(-2.0 * std::log(options_.min_probability)),
      lever_xy_m_(x_body_camera.head<2>().norm()) {}

std::optional<LinkHypothesis> LinkProposer::evaluate(const Esdf& filter,
                                                     const CovarianceBounds& bounds,
                                                     const StateRecovery& recovery, int block,
                                                     double altitude_i_m,
                                                     double altitude_j_m) const {
  // Step 1 needs only the 2x2 horizontal parts of the joint (same numbers as the full joint).
  const Eigen::Matrix2d sigma_ir_xy = recovery.solution().block<2, 2>(Eigen::Index{block} * kD, 1);
  Eigen::Matrix2d C;
  if (!bounds.offset_covariance_2d(block, sigma_ir_xy, &C).ok()) return std::nullopt;
  const Vec6 x_r = filter.mean_block(Esdf::kRobotBlock).head<6>();
  const Vec6 x_i = filter.mean_block(block).head<6>();
  const double lambda_max =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C, Eigen::EigenvaluesOnly).eigenvalues()(1);
  const double reach_m = (altitude_i_m + altitude_j_m) * half_extent_per_altitude_.norm() +
                         2.0 * lever_xy_m_;
  if (!((x_i - x_r).head<2>().norm() - std::sqrt(prefilter_chi2_ * std::max(lambda_max, 0.0)) <
        reach_m)) {
    return std::nullopt;
  }
  LinkHypothesis h;
  if (!bounds.propose(block, recovery.cross_covariance(block), &h.joint).ok()) return std::nullopt;
  try {
    h.x_ri = tail_to_tail(x_r, x_i);
    h.covariance_ri = relative_pose_covariance(pose_joint(h.joint.joint), x_r, x_i);
    Mat6x12 J_mount, J_inverse;
    const Vec6 x_ri_cam = head_to_tail(h.x_ri, x_body_camera_, &J_mount);
    h.x_cr_ci = head_to_tail(inverse_pose(x_body_camera_), x_ri_cam, &J_inverse);
    const Mat6 G = J_inverse.rightCols<6>() * J_mount.leftCols<6>();
    h.covariance_cr_ci = G * h.covariance_ri * G.transpose();
  } catch (const std::domain_error&) {
    return std::nullopt;  // a pitch at ±90°: no relative pose Jacobian
  }
  const FootprintHalfExtent half_j = altitude_j_m * half_extent_per_altitude_;
  const FootprintHalfExtent half_i = altitude_i_m * half_extent_per_altitude_;
  const Eigen::Vector3d mean(h.x_cr_ci(0), h.x_cr_ci(1), h.x_cr_ci(5));
  const int idx[3] = {0, 1, 5};
  Eigen::Matrix3d cov;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) cov(a, b) = h.covariance_cr_ci(idx[a], idx[b]);
  }
  h.overlap_probability =
      overlap_probability(half_j, half_i, mean, cov, options_.min_overlap_fraction);
  if (!(h.overlap_probability >= options_.min_probability)) return std::nullopt;
  h.overlap_at_mean = footprint_overlap_fraction(half_j, half_i, mean.head<2>(), mean(2));
  return h;
}

void LinkProposer::rank_and_cap(std::vector<LinkHypothesis>& hypotheses) const {
  std::stable_sort(hypotheses.begin(), hypotheses.end(),
                   [](const LinkHypothesis& a, const LinkHypothesis& b) {
                     if (a.overlap_probability != b.overlap_probability) {
                       return a.overlap_probability > b.overlap_probability;
                     }
                     if (a.overlap_at_mean != b.overlap_at_mean) {
                       return a.overlap_at_mean > b.overlap_at_mean;
                     }
                     return a.joint.state < b.joint.state;
                   });
  if (hypotheses.size() > static_cast<std::size_t>(options_.max_per_image)) {
    hypotheses.resize(static_cast<std::size_t>(options_.max_per_image));
  }
}

}  // namespace nav::core

// Link proposal from the bounds (navigation/link_proposer.h).
#include "nav/core/navigation/link_proposer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "nav/core/navigation/chi_square.h"

namespace nav::core {
namespace {

constexpr int kD = 12;  // block dimension

}  // namespace

LinkProposer::LinkProposer(double confidence, double footprint_per_altitude,
                           const Vec6& x_body_camera)
    : chi2_2dof_(chi_square_quantile(confidence, 2)),
      footprint_per_altitude_(footprint_per_altitude),
      lever_xy_m_(x_body_camera.head<2>().norm()) {}

bool LinkProposer::propose(const Esdf& filter, const CovarianceBounds& bounds,
                           const StateRecovery& recovery, int block, double altitude_i_m,
                           double altitude_j_m, LinkProposal* joint) const {
  // The test needs only the 2x2 horizontal parts of the joint: computed first (the same
  // numbers as from the full joint), the 24x24 joint is built for the proposed pairs only.
  const Eigen::Matrix2d sigma_ir_xy = recovery.solution().block<2, 2>(Eigen::Index{block} * kD, 1);
  Eigen::Matrix2d C;
  if (!bounds.offset_covariance_2d(block, sigma_ir_xy, &C).ok()) return false;
  const Eigen::Vector2d delta =
      filter.mean_block(block).head<2>() - filter.mean_block(Esdf::kRobotBlock).head<2>();
  const double lambda_max =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C, Eigen::EigenvaluesOnly).eigenvalues()(1);
  const double reach_m = altitude_i_m * footprint_per_altitude_ +
                         altitude_j_m * footprint_per_altitude_ + 2.0 * lever_xy_m_;
  if (!(delta.norm() - std::sqrt(chi2_2dof_ * std::max(lambda_max, 0.0)) < reach_m)) {
    return false;
  }
  return bounds.propose(block, recovery.cross_covariance(block), joint).ok();
}

}  // namespace nav::core

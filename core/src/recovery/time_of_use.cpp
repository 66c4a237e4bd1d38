// check_time_of_use: see time_of_use.h.
#include "nav/core/recovery/time_of_use.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/markov_blanket.h"

namespace nav::core {
namespace {

bool at_euler_singularity(const Vec6& x_r, const Vec6& x_i) {
  return pitch_is_singular(x_r[4]) || pitch_is_singular(x_i[4]) ||
         pitch_is_singular(tail_to_tail(x_r, x_i)[4]);
}

double fraction(int part, int whole) {
  return whole > 0 ? static_cast<double>(part) / whole
                   : std::numeric_limits<double>::quiet_NaN();
}

/// The exact state: marginals by selected inversion, the robot column by one solve.
struct ExactState {
  ExactMarginals marginals;
  Eigen::MatrixXd robot_column;  // Σ_*r, dim x d

  ExactState(const InformationMatrix& lambda, int d)
      : marginals(ExactMarginals::compute(lambda.to_sparse(), d)),
        robot_column(marginals.block_column(0)) {}

  Eigen::MatrixXd joint(int i, int d) const {
    Eigen::MatrixXd j(2 * d, 2 * d);
    const Eigen::MatrixXd sigma_ir = robot_column.middleRows(Eigen::Index{i} * d, d);
    j << robot_column.topRows(d), sigma_ir.transpose(), sigma_ir, marginals.marginal(i);
    return 0.5 * (j + j.transpose());
  }
};

}  // namespace

double TimeOfUseStats::bounds_conservative_fraction() const {
  return fraction(bounds_conservative, bounds_checked);
}

double TimeOfUseStats::joints_conservative_fraction() const {
  return fraction(joints_conservative, joints_checked);
}

std::vector<double> TimeOfUseStats::ours() const {
  std::vector<double> v;
  v.reserve(pairs.size());
  for (const TimeOfUsePair& p : pairs) v.push_back(p.ours);
  return v;
}

std::vector<double> TimeOfUseStats::markov_blanket() const {
  std::vector<double> v;
  for (const TimeOfUsePair& p : pairs) {
    if (!std::isnan(p.markov_blanket)) v.push_back(p.markov_blanket);
  }
  return v;
}

void check_time_of_use(const Esdf& filter, const CovarianceBounds& bounds,
                       const StateRecovery& recovery, const TimeOfUseOptions& options,
                       TimeOfUseStats& stats) {
  const int d = filter.block_dim();
  if (d < 6) {
    throw std::invalid_argument("check_time_of_use: block_dim must be >= 6 (6-DOF poses), is " +
                                std::to_string(d));
  }
  const ExactState exact(filter.information(), d);
  ++stats.checks;
  auto conservative = [&](const Eigen::MatrixXd& ours, const Eigen::MatrixXd& truth) {
    double min_eig = 0.0;
    const bool ok = is_conservative(ours, truth, options.tolerance, &min_eig);
    stats.worst_min_eigenvalue = std::min(stats.worst_min_eigenvalue, min_eig);
    return ok;
  };
  ++stats.bounds_checked;
  stats.bounds_conservative += conservative(bounds.robot_bound(), exact.marginals.marginal(0));
  const Vec6 x_r = filter.mean_block(0).head<6>();
  for (int i = 1; i < filter.num_blocks(); ++i) {
    ++stats.bounds_checked;
    stats.bounds_conservative += conservative(bounds.bound(i), exact.marginals.marginal(i));
    LinkProposal p;
    if (!bounds.propose(i, recovery.cross_covariance(i), &p).ok()) continue;
    const Eigen::MatrixXd joint_exact = exact.joint(i, d);
    ++stats.joints_checked;
    stats.joints_conservative += conservative(p.joint, joint_exact);
    const Vec6 x_i = filter.mean_block(i).head<6>();
    if (at_euler_singularity(x_r, x_i)) {
      ++stats.relative_pairs_singular;
      continue;
    }
    const Mat6 rel_exact = relative_pose_covariance(pose_joint(joint_exact), x_r, x_i);
    TimeOfUsePair pair;
    pair.check = stats.checks;
    pair.state = i;
    pair.ours =
        logdet_ratio(relative_pose_covariance(pose_joint(p.joint), x_r, x_i), rel_exact);
    if (options.markov_blanket) {
      const MarkovBlanketResult mb = markov_blanket_joint(filter.information(), 0, i);
      const Mat6 rel_mb = relative_pose_covariance(pose_joint(mb.joint), x_r, x_i);
      pair.markov_blanket = logdet_ratio(rel_mb, rel_exact);
      if (!is_conservative(rel_mb, rel_exact, options.tolerance)) {
        ++stats.markov_blanket_overconfident;
      }
    }
    stats.pairs.push_back(pair);
  }
}

}  // namespace nav::core

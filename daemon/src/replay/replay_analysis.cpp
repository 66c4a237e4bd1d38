// Final analysis of a replay (dive_replay.h analyse()): exact marginals, bound-vs-exact checks
// and the Fig. 3 log-det ratios.
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/markov_blanket.h"
#include "nav/daemon/replay/dive_replay.h"

namespace nav::daemon {
namespace {

constexpr int kD = 12;
constexpr double kConservativeTolerance = 1e-9;  // relative, as the report's check

double logdet_or_nan(const core::Mat6& ours, const core::Mat6& exact) {
  try {
    return core::logdet_ratio(ours, exact);
  } catch (const std::exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

void logdet_rows(NavFilter& slam, const core::ExactMarginals& exact, const core::Vec12& robot,
                 const Eigen::VectorXd& mean, ReplayAnalysis& a) {
  const core::Esdf& esdf = slam.esdf();
  const Eigen::MatrixXd column = exact.block_column(0);  // Σ_{*r}: every exact joint (r, i)
  const Eigen::MatrixXd sigma_rr = exact.marginal(0);
  for (int i = 1; i < esdf.num_blocks(); ++i) {
    core::LinkProposal p;
    if (!slam.bounds().propose(i, slam.recovery().cross_covariance(i), &p).ok()) continue;
    const core::Vec6 x_r = robot.head<6>();
    const core::Vec6 x_i = mean.segment<6>(Eigen::Index{i} * kD);
    LogdetRow row;
    row.state_i = 0;
    row.state_j = i;
    Eigen::MatrixXd exact_joint(2 * kD, 2 * kD);
    const Eigen::MatrixXd sigma_ir = column.middleRows(Eigen::Index{i} * kD, kD);
    exact_joint << sigma_rr, sigma_ir.transpose(), sigma_ir, exact.marginal(i);
    const core::Mat6 exact_rel =
        core::relative_pose_covariance(core::pose_joint(exact_joint), x_r, x_i);
    row.ours = logdet_or_nan(core::relative_pose_covariance(core::pose_joint(p.joint), x_r, x_i),
                             exact_rel);
    try {
      const core::MarkovBlanketResult mb = core::markov_blanket_joint(esdf.information(), 0, i);
      row.markov_blanket = logdet_or_nan(
          core::relative_pose_covariance(core::pose_joint(mb.joint), x_r, x_i), exact_rel);
    } catch (const std::exception&) {
      row.markov_blanket = std::numeric_limits<double>::quiet_NaN();
    }
    a.logdet.push_back(row);
  }
}

}  // namespace

ReplayAnalysis analyse(NavFilter& slam) {
  ReplayAnalysis a;
  const auto start = std::chrono::steady_clock::now();
  if (!slam.initialised()) {
    a.error = "the filter never initialised (no attitude, heading and depth in the log)";
    return a;
  }
  slam.recover_now();
  core::Esdf esdf = slam.esdf();
  if (core::Status s = esdf.recover_mean_direct(); !s.ok()) {
    a.error = "final mean: " + s.to_string();
    return a;
  }
  const Eigen::VectorXd& mean = esdf.mean();
  a.robot_mean = mean.head<12>();
  try {
    const core::ExactMarginals exact =
        core::ExactMarginals::compute(esdf.information().to_sparse(), kD);
    int conservative = 0;
    for (int b = 1; b < esdf.num_blocks(); ++b) {
      StateCheck s;
      s.state = b;
      s.image = slam.image_of_state(b);
      s.mean = mean.segment<12>(Eigen::Index{b} * kD);
      s.bound = slam.bounds().bound(b).topLeftCorner(6, 6);
      s.exact = exact.marginal(b).topLeftCorner(6, 6);
      if (s.image) s.initial_bound = s.image->initial_bound;
      s.conservative = core::is_conservative(s.bound, s.exact, kConservativeTolerance);
      conservative += s.conservative ? 1 : 0;
      a.states.push_back(s);
    }
    a.conservative_fraction =
        a.states.empty() ? 0.0 : static_cast<double>(conservative) / a.states.size();
    logdet_rows(slam, exact, a.robot_mean, mean, a);
  } catch (const std::exception& e) {
    a.error = std::string("exact marginals: ") + e.what();
  }
  a.analysis_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return a;
}

}  // namespace nav::daemon

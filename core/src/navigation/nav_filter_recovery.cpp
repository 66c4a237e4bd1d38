// NavFilter state recovery at images: the warm-start extension, the certificate handed to the
// bounds, and the recovery executor's jobs (navigation/nav_filter.h "Image", "Recovery
// executor"; the schedule: recovery_executor.h).
#include <string>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/recovery/bounds_renewal.h"

namespace nav::core {

void NavFilter::extend_warm_start() {
  if (warm_.predicted) {
    const Vec12 robot = filter_.mean_block(Esdf::kRobotBlock);
    const bool keep = warm_.kept >= 0;
    // extend_for_prediction sets Σ'_rr = A Σ_tt Aᵀ + Q: choose Q so that it is the tracked P.
    const Mat12 Q = warm_.P - warm_.A * warm_.sigma_tt * warm_.A.transpose();
    if (Status s = recovery_.extend_for_prediction(warm_.A, Q, robot, keep, warm_.kept);
        !s.ok()) {
      warn("NavFilter: warm start extension failed (" + s.to_string() +
           "); restarting from the filter mean");
      Eigen::MatrixXd X = Eigen::MatrixXd::Zero(filter_.information().dim(), 13);
      X.col(0) = filter_.mean();
      (void)recovery_.set_solution(X);
    }
  }
  warm_.extended();
}

bool NavFilter::certify(const RecoveryResult& result) {
  warm_.restart(recovery_.robot_covariance());  // the next extension starts from this iterate
  last_relative_residual_ = result.max_relative_residual;
  counters_.max_cg_relative_residual =
      std::max(counters_.max_cg_relative_residual, result.max_relative_residual);
  if (!result.status.ok()) {
    ++counters_.recovery_failures;
    warn("NavFilter: recovery at t = " + std::to_string(time_us_) +
         " us failed: " + result.status.to_string());
    return false;
  }
  // A refactorisation of this Λ gives its exact marginals: the bounds restart from them
  // (bounds.h "Exact refresh"), then the certificate of the recovered column (K1/K2).
  if (Status s = renew_bounds(result, recovery_.refreshed_marginals(), filter_.num_blocks(),
                              bounds_, &renewal_snapshot_);
      !s.ok()) {
    warn("NavFilter: exact refresh of the bounds at t = " + std::to_string(time_us_) +
         " us skipped: " + s.to_string());
  }
  std::function<OldStateEnergy()> old_states;  // K3 of the certificate, a solve: lazily
  if (bounds_.options().old_state_energy) old_states = [&] { return recovery_.old_state_energy(); };
  if (Status s = bounds_.set_recovery(recovery_.robot_covariance(), recovery_.column_residual(),
                                      filter_.num_blocks(), old_states);
      !s.ok()) {
    ++counters_.recovery_failures;
    warn("NavFilter: bounds certificate at t = " + std::to_string(time_us_) +
         " us: " + s.to_string());
    return false;
  }
  return true;
}

bool NavFilter::recover() {
  if (recovery_in_flight()) take_recovery_result();
  extend_warm_start();
  // Synchronous: the PCG iterations; with jobs: 0 iterations, i.e. the true residual of the
  // extended result of the last job on the current Λ (the certificate of bounds.h).
  const RecoveryResult result =
      recovery_.solve(filter_.information(), filter_.information_vector());
  if (!jobs_.enabled()) ++counters_.recoveries;
  if (!certify(result)) return false;
  if (jobs_.enabled()) return true;  // the delayed states took the job's mean at its hand-off
  const Eigen::VectorXd& recovered = recovery_.solution().col(0);
  for (int b = 1; b < filter_.num_blocks(); ++b) {
    (void)filter_.set_mean_block(b, recovered.segment(Eigen::Index{b} * 12, 12));
  }
  return true;
}

bool NavFilter::recover_now() {
  if (!initialised_) return false;
  if (!jobs_.enabled()) return recover();
  if (recovery_in_flight()) take_recovery_result();
  submit_recovery_job();  // restarts the tracker: no step lies between this job and now
  take_recovery_result();
  const RecoveryResult result =
      recovery_.solve(filter_.information(), filter_.information_vector());
  return certify(result);
}

void NavFilter::submit_recovery_job() {
  // Right after the prediction that keeps the image's state: the snapshot's robot then has that
  // state as its only neighbour (the image's links are edges of the kept state). Submitted
  // before that prediction, the robot's link edges made the kept factor delete and re-add the
  // rows of every state linked at the image, deep in the factor: the default dive's replay took
  // 232.6 s instead of 122.3 s (docs/consistency.md "The recovery thread made tight").
  extend_warm_start();
  warm_.restart(recovery_.robot_covariance());  // the steps from here extend the job's result
  jobs_.submit(filter_.information(), filter_.information_vector(), recovery_.solution(), time_us_);
}

void NavFilter::take_recovery_result() {
  const RecoveryOutput& out = jobs_.take();
  ++counters_.recoveries;
  if (!out.result.status.ok()) {
    ++counters_.recovery_failures;
    warn("NavFilter: recovery job taken at t = " + std::to_string(time_us_) +
         " us failed: " + out.result.status.to_string());
    return;
  }
  if (out.solution.rows() != recovery_.solution().rows() ||
      out.solution.cols() != recovery_.solution().cols()) {
    ++counters_.recovery_failures;
    warn("NavFilter: recovery job's result has " + std::to_string(out.solution.rows()) +
         " rows, the warm start " + std::to_string(recovery_.solution().rows()));
    return;
  }
  // The job refined the snapshot's warm start; what the filter did since (predictions, robot
  // updates, a kept state) extends the new iterate at the next image: A and P are recomputed
  // from the job's Σ_tt by the recorded steps (warm_start_tracker.h).
  const int d = 12;
  Mat12 sigma_new = out.solution.block(0, 1, d, d);
  warm_.replay_from(0.5 * (sigma_new + sigma_new.transpose()));
  (void)recovery_.set_solution(out.solution);
  // The job refactored its snapshot's Λ: its exact marginals bound the same states now.
  if (out.marginals.size() > 0) {
    if (Status s = bounds_.refresh_exact(out.marginals, filter_.num_blocks()); !s.ok()) {
      warn("NavFilter: exact refresh of the bounds from the recovery job at t = " +
           std::to_string(time_us_) + " us skipped: " + s.to_string());
    }
  }
  const Eigen::Index blocks = out.solution.rows() / d;
  for (Eigen::Index b = 1; b < blocks; ++b) {
    (void)filter_.set_mean_block(static_cast<int>(b), out.solution.col(0).segment(b * d, d));
  }
}

}  // namespace nav::core

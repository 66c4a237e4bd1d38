// NavFilter state recovery at images: the warm-start extension, the certificate handed to the
// bounds, and the recovery thread's jobs (nav_filter.h "ImageEvent" and "Recovery thread").
#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>

#include "nav/daemon/filter/nav_filter.h"

namespace nav::daemon {

void NavFilter::extend_warm_start() {
  if (predicted_since_recovery_) {
    const core::Vec12 robot = filter_.mean_block(core::Esdf::kRobotBlock);
    const bool keep = kept_since_recovery_ >= 0;
    // extend_for_prediction sets Σ'_rr = A Σ_tt Aᵀ + Q: choose Q so that it is the tracked P.
    const core::Mat12 Q = P_robot_ - A_since_recovery_ * sigma_tt_ * A_since_recovery_.transpose();
    if (core::Status s = recovery_.extend_for_prediction(A_since_recovery_, Q, robot, keep,
                                                         kept_since_recovery_);
        !s.ok()) {
      spdlog::warn("NavFilter: warm start extension failed ({}); restarting from the filter mean",
                   s.to_string());
      Eigen::MatrixXd X = Eigen::MatrixXd::Zero(filter_.information().dim(), 13);
      X.col(0) = filter_.mean();
      (void)recovery_.set_solution(X);
    }
  }
  A_since_recovery_.setIdentity();
  predicted_since_recovery_ = false;
  kept_since_recovery_ = -1;
}

bool NavFilter::certify(const core::RecoveryResult& result) {
  sigma_tt_ = recovery_.robot_covariance();  // the next extension starts from this iterate
  P_robot_ = sigma_tt_;
  last_relative_residual_ = result.max_relative_residual;
  counters_.max_cg_relative_residual =
      std::max(counters_.max_cg_relative_residual, result.max_relative_residual);
  if (!result.status.ok()) {
    ++counters_.recovery_failures;
    spdlog::warn("NavFilter: recovery at t = {} us failed: {}", time_us_,
                 result.status.to_string());
    return false;
  }
  if (core::Status s = bounds_.set_recovery(recovery_.robot_covariance(),
                                            result.column_residual_frobenius, filter_.num_blocks());
      !s.ok()) {
    ++counters_.recovery_failures;
    spdlog::warn("NavFilter: bounds certificate at t = {} us: {}", time_us_, s.to_string());
    return false;
  }
  return true;
}

bool NavFilter::recover() {
  if (recovery_in_flight()) take_recovery_result();
  extend_warm_start();
  // Synchronous: the PCG iterations; with the thread: 0 iterations, i.e. the true residual of
  // the extended result of the last job on the current Λ (the certificate of bounds.h).
  const core::RecoveryResult result =
      recovery_.solve(filter_.information(), filter_.information_vector());
  if (!worker_.worker) ++counters_.recoveries;
  if (!certify(result)) return false;
  if (worker_.worker) return true;  // the delayed states took the thread's mean at its hand-off
  const Eigen::VectorXd& recovered = recovery_.solution().col(0);
  for (int b = 1; b < filter_.num_blocks(); ++b) {
    (void)filter_.set_mean_block(b, recovered.segment(Eigen::Index{b} * 12, 12));
  }
  return true;
}

bool NavFilter::recover_now() {
  if (!initialised_) return false;
  if (!worker_.worker) return recover();
  if (recovery_in_flight()) take_recovery_result();
  extend_warm_start();
  submit_recovery_job();
  take_recovery_result();
  const core::RecoveryResult result =
      recovery_.solve(filter_.information(), filter_.information_vector());
  return certify(result);
}

void NavFilter::submit_recovery_job() {
  worker_.worker->submit(filter_.information(), filter_.information_vector(), recovery_.solution());
  handoff_us_ =
      time_us_ + static_cast<std::int64_t>(std::llround(options_.recovery_handoff_s * 1e6));
}

void NavFilter::take_recovery_result() {
  const RecoveryOutput& out = worker_.worker->wait();
  ++counters_.recoveries;
  if (!out.result.status.ok()) {
    ++counters_.recovery_failures;
    spdlog::warn("NavFilter: recovery thread's job taken at t = {} us failed: {}", time_us_,
                 out.result.status.to_string());
    return;
  }
  if (out.solution.rows() != recovery_.solution().rows() ||
      out.solution.cols() != recovery_.solution().cols()) {
    ++counters_.recovery_failures;
    spdlog::warn("NavFilter: recovery thread's result has {} rows, the warm start {}",
                 out.solution.rows(), recovery_.solution().rows());
    return;
  }
  // The job refined the snapshot's warm start; what the filter did since (predictions, robot
  // updates, a kept state) is still in A, P and the kept block and extends the new iterate at
  // the next image. P follows the new Σ_tt to first order: P += A (Σ'_tt − Σ_tt) Aᵀ.
  const int d = 12;
  core::Mat12 sigma_new = out.solution.block(0, 1, d, d);
  sigma_new = 0.5 * (sigma_new + sigma_new.transpose()).eval();
  const core::Mat12 P_new =
      P_robot_ + A_since_recovery_ * (sigma_new - sigma_tt_) * A_since_recovery_.transpose();
  if (Eigen::LLT<core::Mat12>(P_new).info() == Eigen::Success) {
    P_robot_ = P_new;
    sigma_tt_ = sigma_new;
  } else {
    // Keep the tracked P: the extension then uses Q = P − A Σ'_tt Aᵀ (a warm start only).
    sigma_tt_ = sigma_new;
  }
  (void)recovery_.set_solution(out.solution);
  const Eigen::Index blocks = out.solution.rows() / d;
  for (Eigen::Index b = 1; b < blocks; ++b) {
    (void)filter_.set_mean_block(static_cast<int>(b), out.solution.col(0).segment(b * d, d));
  }
}

}  // namespace nav::daemon

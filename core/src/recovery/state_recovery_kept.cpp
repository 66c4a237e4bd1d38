// The recovery with the kept factor (M = Λ): the mean by refinement and the robot's column
// solved directly (recovery/state_recovery.h "solve_kept").
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

Status StateRecovery::update_kept(const InformationMatrix& lambda, bool refactor) {
  const int spare = options_.kept_factor_spare_blocks;
  const int recent = options_.kept_factor_recent_blocks;
  if (refactor || !kept_.has_factor()) return kept_.factor(lambda, spare, recent);
  const Status s = kept_.update(lambda);
  // Out of reserved slots, or a CHOLMOD failure on a modification: refactor this Λ.
  return s.ok() ? s : kept_.factor(lambda, spare, recent);
}

PcgSummary StateRecovery::kept_step(const SpdOperator& A, const PcgOptions& pcg,
                                    const InformationMatrix& lambda) {
  const Eigen::Index n = solution_.rows();
  const int d = block_dim_;
  PcgSummary summary;
  auto mean = solution_.col(0);
  const auto eta = rhs_.col(0);
  Eigen::MatrixXd& product = workspace_.Q;
  product.resize(n, 1 + d);
  // r₀ = η − Λ μ₀, from μ₀ = 0 when the warm start is further from μ than zero (pcg.h).
  mean_product_rows_ = mean_product_.update(lambda, kept_.rows_changed_by_last_update(), mean,
                                            solve_stamp_, product.col(0));
  if (mean_product_rows_ < 0) A.multiply(mean, product.leftCols(1));
  Eigen::VectorXd r0 = eta - product.col(0);
  if (pcg.restart_worse_than_zero) {
    summary.restarted_columns =
        restart_worse_than_zero(rhs_.leftCols(1), product.leftCols(1), solution_.leftCols(1), r0);
  }
  Eigen::MatrixXd& step = workspace_.Z;
  step.resize(n, 1 + d);
  Eigen::VectorXd changed = r0;
  const int solved = keep_changed_blocks(changed);
  kept_.solve_with_robot_columns(changed, step);  // [Λ⁻¹ r₀' | Λ⁻¹ E_r]
  mean += step.col(0);
  solution_.rightCols(d) = step.rightCols(d);
  A.multiply(solution_, product);  // both residuals by one product
  Eigen::MatrixXd& residual = workspace_.R;
  residual = rhs_ - product;
  // A step that raised the mean's A-norm error keeps μ₀ (pcg.h).
  const auto z = step.col(0);
  if (refinement_step_raised_error(z, r0, residual.col(0))) {
    mean -= z;
    residual.col(0) = r0;
  } else {
    mean_product_.set(product.col(0), solve_stamp_);  // Λμ of the mean this step leaves
  }
  note_mean_residual(residual.col(0), solved == num_blocks());
  mean_step_blocks_ = solved;
  column_residual_ = residual.rightCols(d);
  summary.iterations = 1;
  summary.residual_norm = Eigen::VectorXd::Constant(1, residual.col(0).norm());
  // Further steps of the mean only while each one at least halves its residual (pcg.h).
  const bool done = !(summary.residual_norm[0] < 0.5 * r0.norm()) ||
                    meets_tolerance(pcg, summary.residual_norm[0], eta.norm());
  if (pcg.max_iterations <= 1 || done) return summary;
  mean_left_max_ = -1.0;  // the next step solves all of r₀
  mean_product_.invalidate();  // the further steps move μ
  PcgOptions rest = pcg;
  rest.max_iterations -= 1;
  PcgSummary more =
      solve_refinement(A, kept_, rhs_.leftCols(1), solution_.leftCols(1), rest, workspace_);
  more.iterations += 1;
  more.restarted_columns += summary.restarted_columns;
  return more;
}

int StateRecovery::keep_changed_blocks(Eigen::VectorXd& r0) const {
  const int blocks = num_blocks();
  if (!(mean_left_max_ >= 0.0) || !(mean_left_max_ <= kMeanRoundingGrowth * mean_full_max_)) {
    return blocks;
  }
  int kept = 0;
  for (int b = 0; b < blocks; ++b) {
    auto block = r0.segment(Eigen::Index{b} * block_dim_, block_dim_);
    if (block.lpNorm<Eigen::Infinity>() > mean_left_max_) {
      ++kept;
    } else {
      block.setZero();
    }
  }
  return kept;
}

void StateRecovery::note_mean_residual(const Eigen::Ref<const Eigen::VectorXd>& residual,
                                       bool full) {
  mean_left_max_ = residual.lpNorm<Eigen::Infinity>();
  if (full) mean_full_max_ = mean_left_max_;
}

RecoveryResult StateRecovery::solve_kept(const SpdOperator& A, const Eigen::VectorXd& eta,
                                         const InformationMatrix& lambda) {
  RecoveryResult result;
  result.mode = options_.mode;
  fill_rhs(eta);
  const PcgOptions pcg = pcg_options(options_.iterations_after_refresh);
  const int d = block_dim_;
  const double target = options_.mode == RecoveryMode::kTolerance ? options_.relative_tolerance
                                                                  : options_.refresh_residual;
  // No iterations: only the residuals of the warm start (the recovery thread's certificate).
  const PcgSummary mean =
      pcg.max_iterations > 0
          ? kept_step(A, pcg, lambda)
          : solve_refinement(A, kept_, rhs_.leftCols(1), solution_.leftCols(1), pcg, workspace_);
  result.status = mean.status;
  result.iterations = mean.iterations;
  result.mean_step_blocks = pcg.max_iterations > 0 ? mean_step_blocks_ : 0;
  result.mean_product_rows = pcg.max_iterations > 0 ? mean_product_rows_ : -1;
  if (!result.status.ok()) return result;
  if (pcg.max_iterations == 0) {
    column_residual_.resize(solution_.rows(), d);
    A.multiply(solution_.rightCols(d), column_residual_);
    column_residual_ = rhs_.rightCols(d) - column_residual_;
  }
  Eigen::VectorXd column_norm = column_residual_.colwise().norm().transpose();
  // On badly conditioned Λ a refinement of the direct solve is more accurate than it.
  if (pcg.max_iterations > 0 && !(column_norm.maxCoeff() <= target)) {
    const PcgSummary column =
        solve_refinement(A, kept_, rhs_.rightCols(d), solution_.rightCols(d), pcg, workspace_);
    result.status = column.status;
    if (!result.status.ok()) return result;
    column_residual_ = workspace_.R.topLeftCorner(solution_.rows(), d);
    column_norm = column.residual_norm;
  }
  Eigen::VectorXd residual_norm(1 + d);
  residual_norm << mean.residual_norm[0], column_norm;
  finish(result, residual_norm, rhs_.colwise().norm().transpose());
  set_spectral(result, column_residual_.transpose() * column_residual_);
  return result;
}

}  // namespace nav::core

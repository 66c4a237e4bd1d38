// Mean and robot-column recovery with warm start (see recovery/state_recovery.h).
#include "nav/core/recovery/state_recovery.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nav::core {
namespace {

std::string shape(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + "x" + std::to_string(m.cols());
}

}  // namespace

const char* to_string(RecoveryMode mode) {
  switch (mode) {
    case RecoveryMode::kFixedIterations: return "fixed-iterations";
    case RecoveryMode::kTolerance: return "tolerance";
    case RecoveryMode::kDirect: return "direct";
  }
  return "unknown";
}

const char* to_string(RecoveryKernel kernel) {
  switch (kernel) {
    case RecoveryKernel::kPacked: return "packed";
    case RecoveryKernel::kGeneric: return "generic";
  }
  return "unknown";
}

const char* to_string(RecoveryPreconditioner preconditioner) {
  switch (preconditioner) {
    case RecoveryPreconditioner::kBlockJacobi: return "block-jacobi";
    case RecoveryPreconditioner::kFactor: return "factor";
  }
  return "unknown";
}

Status StateRecoveryOptions::validate() const {
  if (iterations_per_step < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.iterations_per_step must be >= 0, got " +
                             std::to_string(iterations_per_step));
  }
  if (!(relative_tolerance > 0.0) || !std::isfinite(relative_tolerance)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.relative_tolerance must be finite and > 0, got " +
                             std::to_string(relative_tolerance));
  }
  if (refresh_interval < 1 || !(refresh_residual > 0.0)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions: refresh_interval must be >= 1 and "
                         "refresh_residual > 0, got " + std::to_string(refresh_interval) +
                             " and " + std::to_string(refresh_residual));
  }
  if (iterations_after_refresh < 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.iterations_after_refresh must be >= 1, got " +
                             std::to_string(iterations_after_refresh));
  }
  if (kept_factor_spare_blocks < 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.kept_factor_spare_blocks must be >= 1, got " +
                             std::to_string(kept_factor_spare_blocks));
  }
  if (kept_factor_recent_blocks < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.kept_factor_recent_blocks must be >= 0, got " +
                             std::to_string(kept_factor_recent_blocks));
  }
  if (max_iterations < 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.max_iterations must be >= 1, got " +
                             std::to_string(max_iterations));
  }
  if (!(refresh_growth >= 0.0 && std::isfinite(refresh_growth))) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.refresh_growth must be finite and >= 0, got " +
                             std::to_string(refresh_growth));
  }
  const bool kept = preconditioner == RecoveryPreconditioner::kFactor && keep_factor_equal;
  if (renewal_lag < 0 || (renewal_lag > 0 && !(kept && renewal_lag < refresh_interval))) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecoveryOptions.renewal_lag must be 0, or in [1, refresh_interval) "
                         "with the kept factor; got " +
                             std::to_string(renewal_lag) + " (refresh_interval " +
                             std::to_string(refresh_interval) + ")");
  }
  return Status::Ok();
}

StateRecovery::StateRecovery(int block_dim, StateRecoveryOptions options)
    : block_dim_(block_dim), options_(options) {
  if (block_dim < 1 || block_dim > InformationMatrix::kMaxBlockDim) {
    throw std::invalid_argument("StateRecovery: block_dim must be in [1, 12], got " +
                                std::to_string(block_dim));
  }
  if (Status s = options.validate(); !s.ok()) throw std::invalid_argument(s.message());
  solution_.resize(0, 1 + block_dim_);
}

Status StateRecovery::set_options(const StateRecoveryOptions& options) {
  if (Status s = options.validate(); !s.ok()) return s;
  options_ = options;
  mean_product_.invalidate();
  return Status::Ok();
}

Status StateRecovery::initialize(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0) {
  if (x0.size() != block_dim_ || P0.rows() != block_dim_ || P0.cols() != block_dim_) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::initialize: expected x0 of " +
                             std::to_string(block_dim_) + " and P0 square of that size, got " +
                             std::to_string(x0.size()) + " and " + shape(P0));
  }
  solution_.resize(block_dim_, 1 + block_dim_);
  solution_.col(0) = x0;
  solution_.rightCols(block_dim_) = 0.5 * (P0 + P0.transpose());
  factor_.reset();
  kept_.reset();
  renewal_.drop();
  solves_since_refresh_ = 0;
  previous_blocks_ = 0;
  last_column_residual_ = 0.0;
  mean_left_max_ = -1.0;
  mean_product_.invalidate();
  return Status::Ok();
}

Status StateRecovery::set_solution(const Eigen::MatrixXd& X) {
  if (X.cols() != 1 + block_dim_ || X.rows() % block_dim_ != 0 || X.rows() == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::set_solution: expected n x " +
                             std::to_string(1 + block_dim_) + " with n a multiple of " +
                             std::to_string(block_dim_) + ", got " + shape(X));
  }
  solution_ = X;
  mean_left_max_ = -1.0;
  mean_product_.invalidate();
  return Status::Ok();
}

Eigen::MatrixXd StateRecovery::robot_covariance() const {
  const auto S = solution_.block(0, 1, block_dim_, block_dim_);
  return 0.5 * (S + S.transpose());
}

Eigen::MatrixXd StateRecovery::cross_covariance(int block) const {
  return solution_.block(Eigen::Index{block} * block_dim_, 1, block_dim_, block_dim_);
}

Status StateRecovery::extend_for_prediction(const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q,
                                            const Eigen::VectorXd& robot_mean,
                                            bool keep_current, int kept_block) {
  const int d = block_dim_;
  if (num_blocks() == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::extend_for_prediction: not initialised");
  }
  if (F.rows() != d || F.cols() != d || Q.rows() != d || Q.cols() != d ||
      robot_mean.size() != d) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::extend_for_prediction: F " + shape(F) + ", Q " +
                             shape(Q) + ", mean " + std::to_string(robot_mean.size()) +
                             " must all be of block size " + std::to_string(d));
  }
  if (keep_current && kept_block != num_blocks()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::extend_for_prediction: the kept state must be appended "
                         "as block " + std::to_string(num_blocks()) + ", got " +
                             std::to_string(kept_block));
  }
  const Eigen::MatrixXd sigma_tt = robot_covariance();
  const Eigen::VectorXd mean_t = solution_.col(0).head(d);
  const Eigen::Index old_rows = solution_.rows();
  if (keep_current) solution_.conservativeResize(old_rows + d, Eigen::NoChange);
  auto column = solution_.rightCols(d);
  // Every other state i: Σ'_{i r} = Σ_{i t} Fᵀ.
  if (old_rows > d) {
    column.middleRows(d, old_rows - d) = column.middleRows(d, old_rows - d) * F.transpose();
  }
  if (keep_current) {
    solution_.block(old_rows, 0, d, 1) = mean_t;
    column.bottomRows(d) = sigma_tt * F.transpose();
  }
  const Eigen::MatrixXd sigma_rr = F * sigma_tt * F.transpose() + Q;
  column.topRows(d) = 0.5 * (sigma_rr + sigma_rr.transpose());
  solution_.block(0, 0, d, 1) = robot_mean;
  mean_product_.moved(0);
  if (keep_current) mean_product_.moved(kept_block);
  return Status::Ok();
}

Status StateRecovery::extend_for_augmentation(int new_block) {
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(block_dim_, block_dim_);
  if (num_blocks() == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::extend_for_augmentation: not initialised");
  }
  return extend_for_prediction(I, Eigen::MatrixXd::Zero(block_dim_, block_dim_),
                               solution_.col(0).head(block_dim_), true, new_block);
}

Status StateRecovery::check_snapshot(Eigen::Index n, Eigen::Index eta_size) const {
  if (n != solution_.rows() || eta_size != n) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "StateRecovery::solve: snapshot has " + std::to_string(n) +
                             " rows and eta " + std::to_string(eta_size) +
                             " but the warm start has " + std::to_string(solution_.rows()) +
                             " (extend it on every prediction/augmentation)");
  }
  return Status::Ok();
}

void StateRecovery::fill_rhs(const Eigen::VectorXd& eta) {
  const Eigen::Index n = solution_.rows();
  rhs_.setZero(n, 1 + block_dim_);
  rhs_.col(0) = eta;
  rhs_.block(0, 1, block_dim_, block_dim_).setIdentity();
}

void StateRecovery::finish(RecoveryResult& result, const Eigen::VectorXd& residual_norm,
                           const Eigen::VectorXd& rhs_norm) const {
  result.mean_relative_residual =
      rhs_norm[0] > 0.0 ? residual_norm[0] / rhs_norm[0] : residual_norm[0];
  result.column_relative_residual = 0.0;
  double sum_sq = 0.0;
  for (int c = 1; c <= block_dim_; ++c) {
    result.column_relative_residual =
        std::max(result.column_relative_residual, residual_norm[c] / rhs_norm[c]);
    sum_sq += residual_norm[c] * residual_norm[c];
  }
  result.column_residual_frobenius = std::sqrt(sum_sq);
  result.max_relative_residual =
      std::max(result.mean_relative_residual, result.column_relative_residual);
}

void StateRecovery::set_spectral(RecoveryResult& result, const Eigen::MatrixXd& gram) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (gram + gram.transpose()),
                                                           Eigen::EigenvaluesOnly);
  // λmax(RᵀR) = ‖R‖₂²; never report more than the Frobenius norm (rounding).
  result.column_residual_spectral = std::min(
      result.column_residual_frobenius, std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())));
}

PcgOptions StateRecovery::pcg_options(int iteration_cap) const {
  PcgOptions pcg;
  if (options_.mode == RecoveryMode::kFixedIterations) {
    pcg.max_iterations = iteration_cap >= 0 ? std::min(options_.iterations_per_step, iteration_cap)
                                            : options_.iterations_per_step;
    pcg.relative_tolerance = 0.0;
  } else {
    pcg.max_iterations = options_.max_iterations;
    pcg.relative_tolerance = options_.relative_tolerance;
  }
  pcg.recompute_true_residual = options_.recompute_true_residual;
  return pcg;
}

void StateRecovery::note_convergence(RecoveryResult& result, const PcgSummary& summary) const {
  // Not an error (see the header): the bounds are certified from the residual reached.
  result.hit_iteration_cap =
      result.status.ok() && options_.mode == RecoveryMode::kTolerance && !summary.converged;
}

RecoveryResult StateRecovery::solve_with(const SpdOperator& A, const Preconditioner& M,
                                         const Eigen::VectorXd& eta, int iteration_cap) {
  RecoveryResult result;
  result.mode = options_.mode;
  result.refactored_blocks = preconditioner_.num_blocks();
  fill_rhs(eta);
  const PcgOptions pcg = pcg_options(iteration_cap);
  const PcgSummary summary = solve_pcg(A, M, rhs_, solution_, pcg, workspace_);
  result.status = summary.status;
  result.iterations = summary.iterations;
  if (summary.residual_norm.size() == rhs_.cols()) {
    finish(result, summary.residual_norm, rhs_.colwise().norm().transpose());
    // The workspace holds the final residual R = B - A X (n x (1 + d)).
    const auto R = workspace_.R.topLeftCorner(rhs_.rows(), rhs_.cols()).rightCols(block_dim_);
    column_residual_ = R;
    set_spectral(result, R.transpose() * R);
  }
  note_convergence(result, summary);
  return result;
}

RecoveryResult StateRecovery::solve_factor(const InformationMatrix& lambda,
                                           const Eigen::VectorXd& eta) {
  RecoveryResult result;
  result.mode = options_.mode;
  const bool kept = options_.keep_factor_equal;
  const bool missed = !(last_column_residual_ <= options_.refresh_residual);
  const bool refresh = refresh_now(lambda, missed);
  if (refresh) {
    result.status = factor_.refresh(lambda.to_sparse(), block_dim_);
    if (!result.status.ok()) return result;
    solves_since_refresh_ = 0;
  }
  RecoveryResult renewal;  // the lagged renewal's flags
  if (lagged()) {
    result.status = renew_lagged(lambda, renewal);
    if (!result.status.ok()) return result;
  }
  result.status = kept ? update_kept(lambda, missed)
                       : factor_.update_trailing(lambda);
  if (!result.status.ok()) return result;
  const int cap = refresh ? options_.iterations_after_refresh : -1;
  const auto solve = [&](const SpdOperator& A) {
    return kept ? solve_kept(A, eta, lambda) : solve_with(A, factor_, eta, cap);
  };
  if (options_.kernel == RecoveryKernel::kPacked) {
    packed_operator_.refresh(lambda);
    result = solve(PackedSpdOperator(packed_operator_, packed_rhs_, packed_solution_));
  } else {
    result = solve(InformationOperator(lambda));
  }
  const KeptFactorUpdate& u = kept_.last_update();
  result.refactored_blocks =
      kept ? u.rows_replaced + u.pivots_modified + u.rows_added + u.blocks_updated
           : static_cast<int>((lambda.dim() - factor_.factored_dim()) / block_dim_);
  result.refreshed = refresh;
  result.renewed_earlier = renewal.renewed_earlier;
  result.renewal_started = renewal.renewal_started;
  ++solves_since_refresh_;
  previous_blocks_ = lambda.num_blocks();
  last_column_residual_ = result.column_relative_residual;
  return result;
}

bool StateRecovery::refresh_now(const InformationMatrix& lambda, bool missed) const {
  const bool kept = options_.keep_factor_equal;
  if (lagged() && renewal_.in_flight()) return false;
  const bool first = !factor_.has_factor() || factor_.factored_dim() > lambda.dim();
  // The map's size crossed a power of 1 + refresh_growth since the previous solve: a schedule
  // of the size alone, so that a restored filter (no factor, no counters) keeps it.
  const auto level = [&](int blocks) {
    return blocks < 1 ? -1 : std::floor(std::log(blocks) / std::log1p(options_.refresh_growth));
  };
  const bool grown =
      options_.refresh_growth > 0.0 && level(lambda.num_blocks()) > level(previous_blocks_);
  const bool interval = solves_since_refresh_ >= options_.refresh_interval;
  return first || grown || (!lagged() && (interval || (missed && !kept)));
}

Status StateRecovery::renew_lagged(const InformationMatrix& lambda, RecoveryResult& flags) {
  if (renewal_.in_flight() && renewal_.age() >= options_.renewal_lag) {
    std::shared_ptr<const ExactMarginals> marginals;
    if (Status s = renewal_.take(&marginals); !s.ok()) return s;
    factor_.adopt(std::move(marginals));
    flags.renewed_earlier = true;
  }
  if (solves_since_refresh_ >= options_.refresh_interval && !renewal_.in_flight()) {
    renewal_.start(lambda.to_sparse(), block_dim_);
    flags.renewal_started = true;
    solves_since_refresh_ = 0;
  }
  renewal_.count_solve();
  return Status::Ok();
}

RecoveryResult StateRecovery::solve_packed(const InformationMatrix& lambda,
                                           const Eigen::VectorXd& eta) {
  RecoveryResult result;
  result.mode = options_.mode;
  result.status = packed_preconditioner_.update(lambda);
  if (!result.status.ok()) return result;
  result.refactored_blocks = packed_preconditioner_.last_refactored();
  packed_operator_.refresh(lambda);
  const int d = block_dim_;
  const int columns = 1 + d;
  const int width = packed_width(columns);
  const Eigen::Index n = solution_.rows();
  // B = [η | E_r] packed: η in column 0, the identity in the robot rows (block 0).
  const auto packed_size = static_cast<size_t>(n * width);
  if (packed_rhs_.capacity() < packed_size) {
    packed_rhs_.reserve(std::max(packed_size, packed_rhs_.capacity() * 3 / 2));
  }
  packed_rhs_.assign(packed_size, 0.0);
  for (Eigen::Index i = 0; i < n; ++i) packed_rhs_[static_cast<size_t>(i * width)] = eta[i];
  for (int r = 0; r < d; ++r) packed_rhs_[static_cast<size_t>(r * width + 1 + r)] = 1.0;
  pack_columns(solution_, width, &packed_solution_);
  const PcgSummary summary =
      solve_pcg_packed(packed_operator_, packed_preconditioner_, packed_rhs_.data(),
                       packed_solution_.data(), columns, width, pcg_options(), packed_workspace_);
  unpack_columns(packed_solution_, width, solution_);
  result.status = summary.status;
  result.iterations = summary.iterations;
  if (summary.residual_norm.size() == columns) {
    Eigen::VectorXd rhs_norm = Eigen::VectorXd::Ones(columns);
    rhs_norm[0] = eta.norm();
    finish(result, summary.residual_norm, rhs_norm);
    set_spectral(result,
                 packed_gram(packed_workspace_.R.data(), n, width, 1, block_dim_));
    column_residual_.resize(n, block_dim_);
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int c = 0; c < block_dim_; ++c) {
        column_residual_(i, c) = packed_workspace_.R[static_cast<size_t>(i * width + 1 + c)];
      }
    }
  }
  note_convergence(result, summary);
  return result;
}

RecoveryResult StateRecovery::solve_direct(const Eigen::SparseMatrix<double>& lambda,
                                           const Eigen::VectorXd& eta) {
  RecoveryResult result;
  result.mode = RecoveryMode::kDirect;
  fill_rhs(eta);
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt(lambda);
  if (llt.info() != Eigen::Success) {
    result.status = Status::Error(StatusCode::kNotPositiveDefinite,
                                  "StateRecovery: CHOLMOD could not factor the " +
                                      std::to_string(lambda.rows()) +
                                      "-dimensional information matrix (not SPD)");
    return result;
  }
  solution_ = llt.solve(rhs_);
  const Eigen::MatrixXd residual = rhs_ - lambda * solution_;
  finish(result, residual.colwise().norm().transpose(), rhs_.colwise().norm().transpose());
  const auto R = residual.rightCols(block_dim_);
  column_residual_ = R;
  set_spectral(result, R.transpose() * R);
  return result;
}

RecoveryResult StateRecovery::solve(const CsrMatrix& lambda, const Eigen::VectorXd& eta) {
  ++solve_stamp_;
  RecoveryResult result;
  result.mode = options_.mode;
  result.status = check_snapshot(lambda.rows(), eta.size());
  if (!result.status.ok()) return result;
  if (options_.mode == RecoveryMode::kDirect) {
    // A symmetric CSR matrix is its own transpose, i.e. the same arrays read as CSC.
    return solve_direct(Eigen::SparseMatrix<double>(lambda), eta);
  }
  result.status = preconditioner_.factor(lambda, block_dim_);
  if (!result.status.ok()) return result;
  return solve_with(CsrOperator(lambda), preconditioner_, eta);
}

RecoveryResult StateRecovery::solve(const InformationMatrix& lambda, const Eigen::VectorXd& eta) {
  ++solve_stamp_;
  RecoveryResult result;
  result.mode = options_.mode;
  if (lambda.block_dim() != block_dim_) {
    result.status = Status::Error(StatusCode::kInvalidArgument,
                                  "StateRecovery::solve: information matrix block size " +
                                      std::to_string(lambda.block_dim()) + " != " +
                                      std::to_string(block_dim_));
    return result;
  }
  result.status = check_snapshot(lambda.dim(), eta.size());
  if (!result.status.ok()) return result;
  if (options_.mode == RecoveryMode::kDirect) return solve_direct(lambda.to_sparse(), eta);
  if (options_.preconditioner == RecoveryPreconditioner::kFactor) return solve_factor(lambda, eta);
  if (options_.kernel == RecoveryKernel::kPacked) return solve_packed(lambda, eta);
  result.status = preconditioner_.factor(lambda);
  if (!result.status.ok()) return result;
  return solve_with(InformationOperator(lambda), preconditioner_, eta);
}

}  // namespace nav::core

#pragma once
// State recovery for the exactly sparse delayed-state filter (Eustice et al., RSS 2005,
// sec. III-A): from a snapshot of the information form (Λ, η) recover the mean μ and the
// robot's covariance column Σ_{*r} by solving
//     Λ [μ, Σ_{*r}] = [η, E_r]        (n x (1 + block_dim) right-hand sides)
// with multi-RHS PCG (pcg.h), warm-started from the previous step.
//
// Layout: the robot is block 0 (the ESDF convention, filter/esdf.h); the solution matrix is
// X = [μ | Σ_{*r}], so rows of block i hold μ_i and Σ_{i r}.
//
// Warm-start extension when the filter predicts (x_{t+1} = f(x_t) + w, F = ∂f/∂x_t, w ~ N(0,Q)).
// These rules are EXACT: if X was the exact solution for the old (Λ, η), the extended X is the
// exact solution for the predicted (Λ', η') (tested in state_recovery_test.cpp):
//   * new robot rows (block 0):   μ'_r = f(μ_t),  Σ'_{rr} = F Σ_tt Fᵀ + Q
//   * every other state i:        μ'_i = μ_i,     Σ'_{i r} = Σ_{i t} Fᵀ      (Cov(x_i, f(x_t)+w))
//   * the old robot, when kept as a delayed state (appended as the last block):
//                                 μ'_k = μ_t,     Σ'_{k r} = Σ_tt Fᵀ
// Inserting a delayed copy of the robot without a prediction (x_k = x_r) is the special case
// F = I, Q = 0 of the last rule: its rows equal the robot's (extend_for_augmentation).
// Σ_tt is symmetrised before use (a truncated CG column is not exactly symmetric).
//
// Modes: a fixed number of PCG iterations per step (the paper's real-time mode; the residual
// says how approximate), PCG to a relative-residual tolerance or an iteration cap per step,
// and a direct CHOLMOD solve (reference). Reaching the cap is NOT an error (block-Jacobi PCG
// stagnates on badly conditioned Λ): the result carries hit_iteration_cap and the residual,
// from which the certified bounds (bounds.h) stay conservative (only looser). Preconditioners:
// block Jacobi, or a Cholesky factor of Λ refreshed every few steps (factor_preconditioner.h)
// or kept equal to Λ by modifications at every step (kept_equal_factor.h). With the kept factor
// Σ_{*r} is solved directly rather than from its warm start: the robot's rows are the factor's
// last, so the solve reads the factor once instead of twice (solve_kept).
//
// Not thread-safe: owned by the recovery thread. No clocks (time it from the caller).

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/factor_preconditioner.h"
#include "nav/core/recovery/kept_equal_factor.h"
#include "nav/core/recovery/lagged_renewal.h"
#include "nav/core/recovery/mean_product.h"
#include "nav/core/recovery/packed_pcg.h"
#include "nav/core/recovery/pcg.h"
#include "nav/core/recovery/recovery_options.h"
#include "nav/core/status.h"

namespace nav::core {

class StateRecovery {
 public:
  /// block_dim in [1, 12]; options must validate (std::invalid_argument otherwise: a
  /// configuration error caught at start-up).
  explicit StateRecovery(int block_dim, StateRecoveryOptions options = {});

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return static_cast<int>(solution_.rows() / block_dim_); }
  const StateRecoveryOptions& options() const { return options_; }
  Status set_options(const StateRecoveryOptions& options);

  /// Starts with one state (the robot): μ = x0, Σ_{*r} = P0 (exact for the prior (x0, P0)); drops
  /// the factor (a new filter: the certificate's K3 premise needs a Λ₀ of the same filter).
  Status initialize(const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0);
  /// Replaces the warm start, n x (1 + block_dim) with n a multiple of block_dim.
  Status set_solution(const Eigen::MatrixXd& X);

  /// Extends the warm start across a prediction (rules in the file comment). robot_mean is
  /// f(μ_t), the filter's new robot mean. When keep_current, the old robot becomes the last
  /// block (`kept_block` must equal the old num_blocks()).
  Status extend_for_prediction(const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q,
                               const Eigen::VectorXd& robot_mean, bool keep_current,
                               int kept_block);
  /// Appends a delayed copy of the robot (no prediction): new rows equal the robot's.
  Status extend_for_augmentation(int new_block);

  /// Solves on a CSR snapshot of Λ (both triangles) and η, from the current warm start. On a
  /// size or preconditioner error the warm start is left as it was; after a CG breakdown
  /// (operator not SPD) it holds the iterate reached. status says why.
  RecoveryResult solve(const CsrMatrix& lambda, const Eigen::VectorXd& eta);
  /// Same on the filter's block matrix (kDirect converts to a sparse matrix first).
  RecoveryResult solve(const InformationMatrix& lambda, const Eigen::VectorXd& eta);

  /// [μ | Σ_{*r}], n x (1 + block_dim).
  const Eigen::MatrixXd& solution() const { return solution_; }
  Eigen::VectorXd mean() const { return solution_.col(0); }
  Eigen::MatrixXd robot_column() const { return solution_.rightCols(block_dim_); }  ///< Σ_{*r}
  Eigen::MatrixXd robot_covariance() const;  ///< Σ_rr, symmetrised
  /// Σ_{i r} (rows of block i of the robot column), block_dim x block_dim.
  Eigen::MatrixXd cross_covariance(int block) const;
  /// E_r − Λ Σ^_{*r} of the last solve (n x d; recurrence residual without recompute): bounds.h.
  const Eigen::MatrixXd& column_residual() const { return column_residual_; }
  /// kFactor: exact marginals of the last refresh's Λ (null before the first).
  const ExactMarginals* refreshed_marginals() const { return factor_.marginals(); }
  /// Where the renewals of options().renewal_lag > 0 run (lagged_renewal.h; empty: on the
  /// caller, when taken).
  void set_renewal_launcher(MarginalsLauncher launcher) {
    renewal_.set_launcher(std::move(launcher));
  }
  /// kFactor: K3 of the certificate for column_residual() (certificate.h; old_end 0 otherwise).
  OldStateEnergy old_state_energy() const { return factor_.old_state_energy(column_residual_); }

 private:
  /// `iteration_cap` >= 0 lowers the fixed-iteration budget of this solve (-1: none).
  RecoveryResult solve_with(const SpdOperator& A, const Preconditioner& M,
                            const Eigen::VectorXd& eta, int iteration_cap = -1);
  /// With the kept factor (M = Λ): μ by iterative refinement (pcg.h solve_refinement), capped
  /// at iterations_after_refresh; Σ_{*r} solved directly and refined too when its relative
  /// residual exceeds relative_tolerance (kTolerance) or refresh_residual (kFixedIterations).
  /// The residuals are the true ones.
  RecoveryResult solve_kept(const SpdOperator& A, const Eigen::VectorXd& eta,
                            const InformationMatrix& lambda);
  /// solve_kept's first step of μ and the direct Σ_{*r} with one backward pass over the factor
  /// and one product with Λ for both residuals (KeptEqualFactor::solve_with_robot_columns);
  /// later steps of μ by solve_refinement while each halves its residual. Sets
  /// column_residual_. pcg.max_iterations >= 1. Λμ₀ for r₀ from the previous step's product
  /// where Λ and μ did not change (mean_product.h).
  PcgSummary kept_step(const SpdOperator& A, const PcgOptions& pcg,
                       const InformationMatrix& lambda);
  /// The step of μ solves only the blocks of r₀ = η − Λμ that changed since the previous step:
  /// those with an entry above the largest the previous step left (the others hold that step's
  /// rounding), so that the forward pass reads only their reach in the factor. Zeroes the others
  /// and returns the count kept; all blocks after a step that left more than
  /// kMeanRoundingGrowth times the residual of the last step of all blocks (what the skipped
  /// blocks carried grows by each step's rounding), and when no step went before.
  int keep_changed_blocks(Eigen::VectorXd& r0) const;
  void note_mean_residual(const Eigen::Ref<const Eigen::VectorXd>& residual, bool full);
  static constexpr double kMeanRoundingGrowth = 4.0;
  RecoveryResult solve_factor(const InformationMatrix& lambda, const Eigen::VectorXd& eta);
  /// kFactor with keep_factor_equal: brings kept_ to Λ (refactoring when it must).
  Status update_kept(const InformationMatrix& lambda, bool refactor);
  /// Whether this solve refactors Λ itself: the first solve, the map's size past a power of
  /// 1 + refresh_growth, and (without a renewal lag) refresh_interval solves or a missed residual
  /// (the factor preconditioner). With a lag none while a renewal is in flight.
  bool refresh_now(const InformationMatrix& lambda, bool missed) const;
  bool lagged() const { return options_.keep_factor_equal && options_.renewal_lag > 0; }
  /// renewal_lag > 0: takes the renewal in flight when it is renewal_lag solves old, starts one
  /// of Λ after refresh_interval solves; sets flags.renewed_earlier and flags.renewal_started.
  Status renew_lagged(const InformationMatrix& lambda, RecoveryResult& flags);
  RecoveryResult solve_packed(const InformationMatrix& lambda, const Eigen::VectorXd& eta);
  /// The PCG / refinement options of the mode; `iteration_cap` >= 0 lowers the fixed-iteration
  /// budget (kFixedIterations only).
  PcgOptions pcg_options(int iteration_cap = -1) const;
  void note_convergence(RecoveryResult& result, const PcgSummary& summary) const;
  RecoveryResult solve_direct(const Eigen::SparseMatrix<double>& lambda,
                              const Eigen::VectorXd& eta);
  Status check_snapshot(Eigen::Index n, Eigen::Index eta_size) const;
  void fill_rhs(const Eigen::VectorXd& eta);
  void finish(RecoveryResult& result, const Eigen::VectorXd& residual_norm,
              const Eigen::VectorXd& rhs_norm) const;
  /// result.column_residual_spectral from the Gram matrix of the covariance-column residual.
  static void set_spectral(RecoveryResult& result, const Eigen::MatrixXd& gram);

  int block_dim_;
  StateRecoveryOptions options_;
  Eigen::MatrixXd solution_, rhs_;
  BlockJacobiPreconditioner preconditioner_;
  PcgWorkspace workspace_;
  PackedBlockOperator packed_operator_;
  PackedBlockJacobi packed_preconditioner_;
  PackedPcgWorkspace packed_workspace_;
  std::vector<double> packed_rhs_, packed_solution_;
  Eigen::MatrixXd column_residual_;
  FactorPreconditioner factor_;
  KeptEqualFactor kept_;
  LaggedRenewal renewal_;
  int solves_since_refresh_ = 0;
  int previous_blocks_ = 0;  // Λ's blocks at the previous solve
  double last_column_residual_ = 0.0;
  // keep_changed_blocks: the largest |entry| of η − Λμ the last step of μ left (< 0: unknown),
  // and that of the last step that solved all blocks; the blocks the last step solved.
  double mean_left_max_ = -1.0, mean_full_max_ = 0.0;
  int mean_step_blocks_ = 0;
  MeanProduct mean_product_;  // Λμ of the last kept step, stamped with solve_stamp_
  long solve_stamp_ = 0;      // solves so far
  int mean_product_rows_ = -1;
};

}  // namespace nav::core

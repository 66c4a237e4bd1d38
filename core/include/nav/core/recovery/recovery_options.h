#pragma once
// Options and result of the state recovery (state_recovery.h): the solver mode, the kernel of
// the Λ products, the preconditioner and its refresh policy.

#include <Eigen/Core>

#include "nav/core/status.h"

namespace nav::core {

enum class RecoveryMode {
  kFixedIterations,  ///< exactly `iterations_per_step` PCG iterations (real-time mode)
  kTolerance,        ///< PCG until every column meets `relative_tolerance` or max_iterations
                     ///< is reached (ok either way; RecoveryResult::hit_iteration_cap)
  kDirect,           ///< CHOLMOD supernodal Cholesky of the snapshot (reference; O(fill))
};

const char* to_string(RecoveryMode mode);

/// How the PCG modes multiply with Λ when solving on the filter's block matrix.
enum class RecoveryKernel {
  /// packed_pcg.h: Λ read in place through a block view, packed right-hand sides, SIMD tile
  /// kernels, preconditioner blocks re-inverted only when they changed (block_dim 6 and 12
  /// are specialised, other sizes use a generic tile loop).
  kPacked,
  /// pcg.h: InformationMatrix::multiply on column-major blocks, every preconditioner block
  /// re-inverted each solve (the original implementation; kept as the benchmark baseline).
  kGeneric,
};

const char* to_string(RecoveryKernel kernel);

/// Preconditioner of the PCG modes on the filter's block matrix (CSR snapshots: block Jacobi).
enum class RecoveryPreconditioner {
  kBlockJacobi,  ///< blkdiag(Λ_ii) (with `kernel`)
  kFactor,       ///< Cholesky of Λ at a refresh + a dense block over the robot and newer
                 ///< states (factor_preconditioner.h); Λ products by `kernel`; refresh below
};

const char* to_string(RecoveryPreconditioner preconditioner);

struct StateRecoveryOptions {
  RecoveryMode mode = RecoveryMode::kFixedIterations;
  /// kFixedIterations: PCG iterations per step, >= 0 (0 = only re-evaluate the warm start).
  int iterations_per_step = 5;
  /// kTolerance: stop when ‖b_c - Λ x_c‖ <= relative_tolerance ‖b_c‖ for every column, > 0.
  double relative_tolerance = 1e-10;
  /// kTolerance: iteration cap per solve, >= 1; hitting it is not an error (hit_iteration_cap,
  /// the residual reached: the bounds certify from it).
  int max_iterations = 5000;
  /// Solver of the PCG modes on an InformationMatrix (CSR snapshots always use pcg.h).
  RecoveryKernel kernel = RecoveryKernel::kPacked;
  /// PCG modes: recompute the true residual B - Λ X at the end (one more Λ product). false
  /// reports the recurrence residual: only for a caller that certifies elsewhere (NavFilter's
  /// recovery thread: the filter takes the true residual on its current Λ).
  bool recompute_true_residual = true;
  RecoveryPreconditioner preconditioner = RecoveryPreconditioner::kFactor;
  /// kFactor: refactor before a solve when `refresh_interval` solves (>= 1) used the factor, or
  /// when the previous solve left a covariance-column relative residual above
  /// `refresh_residual` (> 0). 1: every solve refactors, so a solve depends only on Λ, η and
  /// the warm start (a checkpointed or copied recovery continues bit-identically; a copy
  /// carries no factor and refactors at its first solve).
  int refresh_interval = 1;
  double refresh_residual = 1e-6;
  /// kFactor: refactor also when Λ's number of blocks passes a power of 1 + refresh_growth (>= 0;
  /// 0: off): refreshes early in a dive, where the map is small (the refresh cheap) and its
  /// marginals shrink fastest, and every refresh_interval solves once it is large. A schedule
  /// of the map's size alone, kept by a restored filter. Never lagged (renewal_lag).
  double refresh_growth = 0.0;
  /// kFactor, kFixedIterations: at most this many iterations (>= 1) in a step that refactored:
  /// M = Λ, the first is the direct solve; later ones drift on rounding noise where the
  /// computed residual cannot see it (docs/consistency.md "Iterations after a refresh").
  int iterations_after_refresh = 1;
  /// kFactor: precondition with a factor kept equal to Λ (kept_equal_factor.h: modified at
  /// every solve, refactored when its `kept_factor_spare_blocks` (>= 1) reserved slots run out
  /// or the residual exceeds refresh_residual) and solved by iterative refinement instead of
  /// PCG (pcg.h solve_refinement), capped at iterations_after_refresh per solve; the refresh
  /// above then only renews the exact marginals. false: blkdiag(P Λ₀ Pᵀ, Λ_TT).
  bool keep_factor_equal = false;
  int kept_factor_spare_blocks = 64;
  /// The newest delayed states (>= 0) that each refactorisation orders after all older ones
  /// (kept_equal_factor.h; 0: plain AMD; docs/performance.md "The newest states ordered last").
  int kept_factor_recent_blocks = 16;
  /// With keep_factor_equal: solves (>= 0, < refresh_interval) from the snapshot of a renewal
  /// of the exact marginals to the solve that takes it (lagged_renewal.h), so that it can run
  /// beside them; the states not tightened since then are reset to those marginals
  /// (RecoveryResult::renewed_earlier). 0: computed and taken within the solve that renews.
  int renewal_lag = 0;
  Status validate() const;
};

struct RecoveryResult {
  Status status;
  RecoveryMode mode = RecoveryMode::kFixedIterations;
  int iterations = 0;                    ///< PCG iterations (0 for kDirect)
  /// kTolerance only: the cap (max_iterations) stopped PCG before every column met the
  /// tolerance. status stays ok; the residuals below say what was reached.
  bool hit_iteration_cap = false;
  double mean_relative_residual = 0.0;   ///< ‖η - Λμ‖ / ‖η‖
  double column_relative_residual = 0.0; ///< max_c ‖e_c - Λσ_c‖ / ‖e_c‖ over the Σ_{*r} columns
  double max_relative_residual = 0.0;    ///< max of the two above
  double column_residual_frobenius = 0.0;  ///< ‖E_r - Λ Σ̂_{*r}‖_F (certificate, bounds.h)
  /// ‖E_r - Λ Σ̂_{*r}‖₂ (<= the Frobenius norm), every mode: the certificate's tighter input.
  double column_residual_spectral = 0.0;
  int refactored_blocks = 0;  ///< preconditioner blocks re-inverted (packed: changed only)
  /// kFactor: this solve refactored Λ (StateRecovery::refreshed_marginals() are of this Λ).
  bool refreshed = false;
  /// renewal_lag > 0: this solve took a renewal of the Λ of renewal_lag solves before
  /// (refreshed_marginals(), of fewer blocks), and whether it started one of this Λ.
  bool renewed_earlier = false;
  bool renewal_started = false;
  /// Kept factor: the blocks of η − Λμ its step of μ solved (the others held only the previous
  /// step's rounding: StateRecovery::keep_changed_blocks); 0 in the other modes.
  int mean_step_blocks = 0;
  /// Kept factor: the block rows of Λμ recomputed for r₀, the others kept from the previous
  /// step's product (mean_product.h); −1 when the whole product was due, or another mode.
  int mean_product_rows = -1;
};

}  // namespace nav::core

#pragma once
// Multi-right-hand-side preconditioned conjugate gradients for the state recovery of the
// exactly sparse delayed-state filter (Eustice et al., RSS 2005, sec. III-A): the mean and the
// robot's covariance column are solved together, Λ [μ, Σ_{*r}] = [η, E_r].
//
// Algorithm: textbook PCG (Hestenes & Stiefel 1952; Saad, "Iterative Methods for Sparse Linear
// Systems", 2nd ed., Alg. 9.1) run on every column at once so that the expensive part, the
// product Λ P, is one sparse-matrix times thin-dense-matrix product per iteration. Each column
// keeps its own step α_c and direction update β_c, so the columns converge independently
// (identical to running the columns one by one); a column that has met the tolerance is frozen.
//
// Preconditioner: block Jacobi, M = blockdiag(Λ_00, Λ_11, ...), whose blocks are inverted once
// per snapshot of Λ (BlockJacobiPreconditioner::factor). The filter's blocks are the natural
// units of Λ (one state each), and block Jacobi makes CG invariant to the very different scales
// of positions, angles and velocities inside a state.
//
// Residuals: at the end of a solve the TRUE residual R = B - A X is recomputed with one extra
// product (unless disabled), because the covariance bounds (bounds.h) certify their error from
// it and the recurrence residual drifts from the true one in floating point.
//
// Allocation: the caller owns a PcgWorkspace; it only reallocates when the problem size grows.
// Thread contract: none of these types are shared; the recovery thread owns them.

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/status.h"

namespace nav::core {

/// Row-major compressed sparse matrix: the snapshot format of Λ for the recovery thread.
using CsrMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// A symmetric positive definite linear operator Y = A X.
class SpdOperator {
 public:
  virtual ~SpdOperator() = default;
  virtual Eigen::Index dim() const = 0;
  /// Y = A X; X and Y are dim() x m (any m >= 1) and do not alias.
  virtual void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                        Eigen::Ref<Eigen::MatrixXd> Y) const = 0;
};

/// Λ as a compressed row-major snapshot (both triangles stored). Holds a reference: the
/// matrix must outlive the operator.
class CsrOperator final : public SpdOperator {
 public:
  explicit CsrOperator(const CsrMatrix& lambda) : lambda_(lambda) {}
  Eigen::Index dim() const override { return lambda_.rows(); }
  void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                Eigen::Ref<Eigen::MatrixXd> Y) const override;

 private:
  const CsrMatrix& lambda_;
};

/// Λ as the filter's block-sparse InformationMatrix (InformationMatrix::multiply). Holds a
/// reference: the matrix must outlive the operator and must not change during a solve.
class InformationOperator final : public SpdOperator {
 public:
  explicit InformationOperator(const InformationMatrix& lambda) : lambda_(lambda) {}
  Eigen::Index dim() const override { return lambda_.dim(); }
  void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                Eigen::Ref<Eigen::MatrixXd> Y) const override {
    lambda_.multiply(X, Y);
  }

 private:
  const InformationMatrix& lambda_;
};

/// A symmetric positive definite preconditioner: Z = M⁻¹ R.
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  virtual Eigen::Index dim() const = 0;
  /// Z = M⁻¹ R (R and Z are dim() x m, no aliasing).
  virtual void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
                     Eigen::Ref<Eigen::MatrixXd> Z) const = 0;
};

/// Block-Jacobi preconditioner: Z = M^-1 R with M the block diagonal of Λ.
class BlockJacobiPreconditioner final : public Preconditioner {
 public:
  /// Inverts the diagonal blocks of a CSR snapshot. kNotPositiveDefinite names the first block
  /// whose Cholesky factorisation fails; kInvalidArgument if the size is not a multiple of
  /// block_dim. On error the preconditioner is left empty.
  Status factor(const CsrMatrix& lambda, int block_dim);
  /// Same from the filter's block matrix (diagonal_block(i)).
  Status factor(const InformationMatrix& lambda);

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return static_cast<int>(inverse_blocks_.size()); }
  Eigen::Index dim() const override { return Eigen::Index{num_blocks()} * block_dim_; }

  /// Z = M^-1 R (R and Z are dim() x m).
  void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
             Eigen::Ref<Eigen::MatrixXd> Z) const override;

 private:
  Status invert_block(int index, const Eigen::Ref<const Eigen::MatrixXd>& block);

  int block_dim_ = 0;
  std::vector<Eigen::MatrixXd> inverse_blocks_;
};

struct PcgOptions {
  /// Maximum iterations (>= 0). 0 only evaluates the residual of the initial guess.
  int max_iterations = 100;
  /// A column stops when ‖b_c - A x_c‖ <= relative_tolerance ‖b_c‖ (>= 0). 0 runs exactly
  /// max_iterations on every column (the fixed-budget real-time mode).
  double relative_tolerance = 0.0;
  /// Recompute R = B - A X with one extra product at the end (recommended; the bounds rely on
  /// it). When false the recurrence residual is reported.
  bool recompute_true_residual = true;
  /// A column whose warm start is further from the solution than x = 0 in the A-norm that CG
  /// minimises restarts from zero: ‖x0 - x*‖²_A - ‖x*‖²_A = x0ᵀA x0 - 2 bᵀx0 > 0. A stale warm
  /// start propagated through many predictions can be arbitrarily bad (errors are multiplied
  /// by F every step); this keeps every column's error from growing without bound under a
  /// fixed budget. (Comparing residual 2-norms instead, ‖b - A x0‖ > ‖b‖, wrongly throws away
  /// good covariance columns: Λ is badly scaled, so a small error in x0 can give a residual
  /// far above ‖e_r‖ = 1 although x0 is much closer to Σ_{*r} than zero is.)
  bool restart_worse_than_zero = true;

  Status validate() const;
};

struct PcgSummary {
  Status status;                       ///< kNumericalFailure if p^T A p <= 0 in some column
  int iterations = 0;                  ///< iterations run (the slowest column)
  Eigen::VectorXd residual_norm;       ///< ‖b_c - A x_c‖_2 per column at exit
  Eigen::VectorXd relative_residual;   ///< residual_norm / ‖b_c‖ (‖r‖ when b_c = 0)
  double max_relative_residual = 0.0;  ///< max over columns
  bool converged = false;              ///< every column met relative_tolerance
  int restarted_columns = 0;           ///< columns restarted from zero (see PcgOptions)
};

/// Scratch matrices of a solve (reused between solves; grows, never shrinks).
struct PcgWorkspace {
  Eigen::MatrixXd R, Z, P, Q;
};

/// Solves A X = B by multi-RHS PCG. X holds the warm start on entry and the solution on exit.
/// A, M, B and X must agree in size (kInvalidArgument otherwise, X untouched).
PcgSummary solve_pcg(const SpdOperator& A, const Preconditioner& M,
                     const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X,
                     const PcgOptions& options, PcgWorkspace& workspace);

/// Solves A X = B by iterative refinement with M a factor of A (Wilkinson 1963; Higham,
/// "Accuracy and Stability of Numerical Algorithms", 2nd ed., ch. 12): per iteration
/// X += M⁻¹(B − A X), then the true residual by one product. With M = A this is the step a PCG
/// iteration takes (its α = rᵀz / zᵀAz is 1), at one product less. A column whose step would
/// raise its A-norm error (zᵀAz > 2 zᵀr, with Az = R_before − R_after: M far from A) keeps its
/// iterate and stops; the residual reported then tells the caller to refactor. A column also
/// stops when a step did not halve its residual norm (the rounding floor: with a tolerance below
/// it, refinement would otherwise run to max_iterations). Same options (restart_worse_than_zero
/// too) and summary as solve_pcg; the residual is always the true one.
PcgSummary solve_refinement(const SpdOperator& A, const Preconditioner& M,
                            const Eigen::Ref<const Eigen::MatrixXd>& B,
                            Eigen::Ref<Eigen::MatrixXd> X, const PcgOptions& options,
                            PcgWorkspace& workspace);

/// The rules solve_refinement applies per column, for callers that take a refinement step
/// their own way (the kept-factor recovery, state_recovery.h):
/// restarts from zero (X = 0, R = B) every column whose warm start is further from the solution
/// than zero in the A-norm (PcgOptions::restart_worse_than_zero); AX = A X. Returns the count.
int restart_worse_than_zero(const Eigen::Ref<const Eigen::MatrixXd>& B,
                            const Eigen::Ref<const Eigen::MatrixXd>& AX,
                            Eigen::Ref<Eigen::MatrixXd> X, Eigen::Ref<Eigen::MatrixXd> R);
/// A column is done when its residual norm meets the relative tolerance (never when it is 0).
bool meets_tolerance(const PcgOptions& options, double residual_norm, double rhs_norm);
/// The step z, which took the residual from r_before to r_after, raised the A-norm error:
/// zᵀAz > 2 zᵀr_before, with Az = r_before − r_after.
bool refinement_step_raised_error(const Eigen::Ref<const Eigen::VectorXd>& z,
                                  const Eigen::Ref<const Eigen::VectorXd>& r_before,
                                  const Eigen::Ref<const Eigen::VectorXd>& r_after);

}  // namespace nav::core

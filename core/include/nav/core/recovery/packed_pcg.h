#pragma once
// Fast path of the state recovery (state_recovery.h): the same multi-RHS block-Jacobi PCG as
// pcg.h, on the filter's block matrix read IN PLACE and on "packed" right-hand sides.
//
// Why (profile of `navtool covariance parking-garage.g2o`, 5 iterations/step, before this
// file): 78 % of the time in InformationMatrix::multiply (dynamic-size blocks times strided
// column-major slices of X), 9 % in the preconditioner apply, 4 % in the PCG vector loops,
// ~3 % refactoring all diagonal blocks every step.
//
// Packed layout: an n x m block of right-hand sides (m = 1 + block_dim: mean + covariance
// columns) is stored row-major with the row padded to `width` = m rounded up to a multiple of
// 8 (packed_width). The d rows of a state are then one contiguous d x width tile, so the
// product of a stored d x d block with them is a register-blocked tile kernel (GCC vector
// extensions, 4 doubles per vector: one AVX2 register, two SSE2 registers; the kernels are
// compiled for x86-64-v4, v3 and the baseline and picked at load time), and
// every per-column dot product of PCG is a contiguous vector reduction. Padding columns are
// zero in B and X and stay zero (their step length is 0).
//
// PackedBlockOperator: a view of Λ (pointers to the stored blocks of an InformationMatrix, no
// copy of the values). refresh() costs O(stored blocks) pointer reads per step; a BSR copy
// would cost a copy or a change detection over all values (the whole matrix) per step, and
// the filter's matrix gives no list of changed blocks.
// PackedBlockJacobi: keeps the inverse of every diagonal block and re-inverts only the blocks
// whose values changed since the previous update (bitwise comparison with a cached copy, d²
// doubles per state; a pose-graph step changes the robot's, the new delayed state's and the
// linked states' diagonal blocks: O(links), not O(n) factorisations).
//
// Not thread-safe: owned by the recovery thread.

#include <Eigen/Core>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/pcg.h"
#include "nav/core/status.h"

namespace nav::core {

/// Row width of a packed n x columns matrix: columns rounded up to a multiple of 8.
int packed_width(int columns);

/// Copies an n x m column-major matrix into packed form (n x width row-major, padding zero).
void pack_columns(const Eigen::Ref<const Eigen::MatrixXd>& M, int width,
                  std::vector<double>* packed);
/// Inverse of pack_columns for the first M.cols() columns.
void unpack_columns(const std::vector<double>& packed, int width, Eigen::Ref<Eigen::MatrixXd> M);

/// Gram matrix G = Aᵀ A of the packed columns [first, first + count) of a packed matrix
/// (rows x width): the input of the spectral norm ‖A‖₂ = sqrt(λmax(G)).
Eigen::MatrixXd packed_gram(const double* A, Eigen::Index rows, int width, int first, int count);

/// Λ (an InformationMatrix) as a block-sparse operator on packed matrices, read in place.
class PackedBlockOperator {
 public:
  /// Rebuilds the view. The pointers stay valid until the next non-const call on `lambda`
  /// (which must outlive every multiply()).
  void refresh(const InformationMatrix& lambda);

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return static_cast<int>(row_start_.size()) - 1; }
  Eigen::Index dim() const { return Eigen::Index{num_blocks()} * block_dim_; }
  /// Stored blocks including the diagonal ones.
  size_t num_stored_blocks() const { return data_.size(); }

  /// Y = Λ X for packed X, Y (dim() x width, width a multiple of 8, no aliasing). When
  /// `column_dots` is not null it receives Σ_rows X ∘ Y per packed column (width values), i.e.
  /// x_cᵀ Λ x_c, fused into the product.
  void multiply(const double* X, double* Y, int width, double* column_dots = nullptr) const;

 private:
  int block_dim_ = 0;
  std::vector<int> row_start_{0};    // stored blocks of block row i: [row_start_[i], [i+1])
  std::vector<int> col_;             // block column of each stored block
  std::vector<const double*> data_;  // d x d column-major values of each stored block
};

/// The packed product behind pcg.h's column-major SpdOperator: packs X, multiplies with the tile
/// kernels, unpacks Y (O(n·width) copies beside the block products). For preconditioners that
/// work on column-major matrices (factor_preconditioner.h). The scratch vectors belong to the
/// caller (reused across solves); operator and scratch must outlive the solve.
class PackedSpdOperator final : public SpdOperator {
 public:
  PackedSpdOperator(const PackedBlockOperator& A, std::vector<double>& x_scratch,
                    std::vector<double>& y_scratch)
      : A_(A), x_(x_scratch), y_(y_scratch) {}
  Eigen::Index dim() const override { return A_.dim(); }
  void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                Eigen::Ref<Eigen::MatrixXd> Y) const override;

 private:
  const PackedBlockOperator& A_;
  std::vector<double>& x_;
  std::vector<double>& y_;
};

/// Block-Jacobi preconditioner on packed matrices with incremental refactorisation.
class PackedBlockJacobi {
 public:
  /// Makes the preconditioner match the diagonal blocks of `lambda`: blocks equal (bitwise) to
  /// those of the previous update keep their inverse, others are re-inverted (Cholesky).
  /// kNotPositiveDefinite names the first failing block; the preconditioner is then reset
  /// (the next update refactors everything).
  Status update(const InformationMatrix& lambda);

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return num_blocks_; }
  /// Diagonal blocks inverted by the last update().
  int last_refactored() const { return last_refactored_; }

  /// Z = M⁻¹ R on packed matrices; when `column_dots` is not null it receives Σ_rows R ∘ Z
  /// per packed column (rᵀ M⁻¹ r), fused into the pass.
  void apply(const double* R, double* Z, int width, double* column_dots = nullptr) const;

 private:
  void reset();

  int block_dim_ = 0;
  int num_blocks_ = 0;
  int last_refactored_ = 0;
  std::vector<double> diagonal_;  // cached Λ_ii, d² each
  std::vector<double> inverse_;   // Λ_ii⁻¹, d² each (column-major)
};

/// Scratch of a packed solve (reused; grows, never shrinks).
struct PackedPcgWorkspace {
  std::vector<double> R, Z, P, Q;
  std::vector<double> scalars;  // per-column α, β, dot products
  std::vector<char> active;     // per-column "still iterating"
};

/// Multi-RHS PCG on packed matrices: exactly the algorithm of solve_pcg (pcg.h: per-column
/// α, β, tolerance freezing, the warm-start restart rule, the final true residual) with
/// `columns` real columns in packed rows of `width`. B and X are dim() x width packed; X holds
/// the warm start on entry and the solution on exit.
PcgSummary solve_pcg_packed(const PackedBlockOperator& A, const PackedBlockJacobi& M,
                            const double* B, double* X, int columns, int width,
                            const PcgOptions& options, PackedPcgWorkspace& workspace);

}  // namespace nav::core

#pragma once
// Exact marginal covariances of a sparse SPD information matrix without a dense inverse:
// the ground truth that covariance bounds are checked against (docs/architecture.md "Core math").
//
// Method: CHOLMOD supernodal Cholesky P Lambda P^T = L L^T with a fill-reducing ordering,
// then selected inversion by the Takahashi recurrences (Takahashi, Fagan & Chen 1973;
// Erisman & Tinney 1975; supernodal form as in Lin et al., "SelInv", ACM TOMS 2011): for each
// supernode with columns J and below-diagonal rows R, processed from the last to the first,
//     Sigma_RJ = -Sigma_RR L_RJ L_JJ^-1,
//     Sigma_JJ = L_JJ^-T (I + L_RJ^T Sigma_RR L_RJ) L_JJ^-1,
// where Sigma_RR is already known because every pair of rows in R lies in the pattern of L.
// The result is Sigma = Lambda^-1 exactly (up to rounding) on the pattern of L, which contains
// the pattern of Lambda: every diagonal block and every block (a, b) with Lambda_ab != 0.
//
// Blocks: the scalar dimension n must be a multiple of block_dim; block b is scalar indices
// [b*block_dim, (b+1)*block_dim).
//
// Typical use (ground truth for bounds):
//   auto em = ExactMarginals::compute(Lambda, 6);
//   Eigen::MatrixXd S_ii = em.marginal(i);      // 6x6
//   Eigen::MatrixXd S_ri = em.joint(r, i);      // 12x12 [[S_rr S_ri]; [S_ir S_ii]]
//
// Cost (measured, core/bench/exact_marginals_bench.cpp): parking-garage (9,966 dims) ~30 ms CPU,
// sphere2500 (15,000 dims) ~150 ms CPU; thousands of times faster than a dense inverse.
// Debian's CHOLMOD is built with CHOLMOD_OMP_NUM_THREADS = 4: its supernodal factorisation
// opens 4-thread OpenMP regions on large supernodes whatever OMP_NUM_THREADS says; run with
// OMP_THREAD_LIMIT=1 to keep it on one core (it is faster on a loaded 2-core machine).
//
// Not thread-safe for concurrent solve() or joint() calls that fall outside the pattern (they
// share one solve workspace); marginal() and in-pattern joint() are const and read-only.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <stdexcept>

namespace nav::core {

/// Lambda is not symmetric positive definite (CHOLMOD reported a non-positive pivot), or its
/// size is not a multiple of the block size. what() names the column/size.
class ExactMarginalsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Fill-reducing ordering used for the factorisation.
enum class MarginalsOrdering {
  kBlockAmd,     ///< AMD on the block graph, expanded to scalars (default; fastest on pose graphs)
  kBlockMetis,   ///< METIS nested dissection on the block graph, expanded to scalars
  kCholmodAuto,  ///< CHOLMOD's default choice (scalar AMD, METIS if AMD fills badly)
};

/// Instruction set of the dense kernels per supernode (Eigen GEMM/triangular products) of the
/// selected inversion and of solve(). Both give the same results up to rounding.
enum class MarginalsKernel {
  kAuto,      ///< AVX2+FMA copy when the CPU has both (checked once at load time), else baseline
  kBaseline,  ///< the project's default instruction set (SSE2 on x86-64); benchmark baseline
};

/// "avx2-fma" or "baseline": what kAuto runs on this CPU.
const char* auto_marginals_kernel_name();

class ExactMarginals {
 public:
  /// Factors Lambda (both triangles stored, or at least the lower one: only the lower
  /// triangle is read) and runs the selected inversion. Throws ExactMarginalsError if Lambda is
  /// not SPD or its size is not a multiple of block_dim, std::invalid_argument if block_dim < 1.
  static ExactMarginals compute(const Eigen::SparseMatrix<double>& Lambda, int block_dim,
                                MarginalsOrdering ordering = MarginalsOrdering::kBlockAmd,
                                MarginalsKernel kernel = MarginalsKernel::kAuto);

  ExactMarginals(ExactMarginals&&) noexcept;
  ExactMarginals& operator=(ExactMarginals&&) noexcept;
  ~ExactMarginals();

  int block_dim() const;
  int num_blocks() const;

  /// Sigma_bb, block_dim x block_dim, exact. O(block_dim^2 log) lookups, no solve.
  Eigen::MatrixXd marginal(int block) const;
  /// Every marginal stacked: block b in rows [b d, (b + 1) d) of num_blocks() d x d.
  Eigen::MatrixXd marginals() const;

  /// Joint covariance of blocks a and b: 2d x 2d [[S_aa S_ab]; [S_ba S_bb]] (a == b allowed:
  /// then all four quadrants equal S_aa). When S_ab is inside the pattern of L (e.g. a and b
  /// adjacent in Lambda) it is read from the selected inverse; otherwise the d columns of
  /// block b are solved exactly with the factor, Lambda X = E_b (two triangular solves,
  /// O(nnz(L) d)), and S_ab is read from X. Either way the result is exact.
  Eigen::MatrixXd joint(int a, int b) const;

  /// The d columns of block b of Lambda⁻¹ (n x d), Lambda X = E_b solved with the factor: with
  /// marginal(i), every exact joint (b, i) without a solve per i.
  Eigen::MatrixXd block_column(int block) const;

  /// X = Lambda⁻¹ B with the factor (two supernodal triangular solves, O(nnz(L) m) for an
  /// n x m B; no allocation after the first call with a given m): the preconditioner of
  /// recovery/factor_preconditioner.h. Throws ExactMarginalsError on a size mismatch (naming
  /// both sizes). Uses the object's solve workspace (not thread-safe).
  void solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X) const;
  /// Bᵀ Lambda⁻¹ B (m x m, symmetric) by the forward solve only (half of solve()'s work):
  /// the certificate's residual energy (recovery/bounds.h). Same errors and workspace as solve.
  Eigen::MatrixXd quadratic_form(const Eigen::Ref<const Eigen::MatrixXd>& B) const;

  /// True when every entry of the off-diagonal block (a, b) lies in the pattern of L, i.e.
  /// joint(a, b) needs no solve.
  bool in_pattern(int a, int b) const;

  /// Sigma_ij for scalar indices, if (i, j) is in the pattern of L; otherwise throws
  /// std::out_of_range. For tests and for callers that need single entries.
  double entry(Eigen::Index i, Eigen::Index j) const;

  /// Wall time of the CHOLMOD analyse + factorise, and of the selected inversion, in ms
  /// (steady clock; for reporting only).
  double factor_ms() const;
  double inversion_ms() const;
  /// Number of stored entries of L (= of the selected inverse), including supernode padding.
  Eigen::Index factor_nnz() const;

 private:
  struct Impl;
  explicit ExactMarginals(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace nav::core

#pragma once
// The factor and selected inverse behind ExactMarginals (recovery/exact_marginals.h). Private to
// core/src/recovery: exact_marginals.cpp factors and inverts, exact_marginals_solve.cpp solves.
//
// Storage: CHOLMOD's supernodal L. Supernode s owns the permuted columns super[s] ..
// super[s+1]-1, a sorted row list (its own columns first) at rows() + pi[s], and a column-major
// nrows x ncols value block at L->x + px[s]. The selected inverse `sigma` has the same layout,
// its diagonal blocks stored in full. Permuted index k is original index perm[k] (CHOLMOD
// factors P Λ Pᵀ as given, in its natural ordering, unless the ordering is CHOLMOD's own).

#include <cholmod.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cstddef>
#include <memory>
#include <vector>

#include "nav/core/recovery/exact_marginals.h"

namespace nav::core {

struct ExactMarginals::Impl {
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  int block_dim = 0;
  int n = 0;
  MarginalsKernel kernel = MarginalsKernel::kAuto;  // of invert() and solve()
  mutable cholmod_common common{};
  cholmod_factor* L = nullptr;
  std::unique_ptr<double[]> sigma;  // same layout as L->x; every entry written by invert()
  std::vector<int> col_super;       // supernode of each (permuted) column
  std::vector<int> perm;            // perm[permuted] = original
  std::vector<int> inv_perm;        // inv_perm[original] = permuted
  double factor_ms = 0.0;
  double inversion_ms = 0.0;
  // Workspace of solve(): the right-hand sides in permuted order and one supernode's rows.
  mutable RowMajorMatrix solve_work, solve_rows;

  Impl() { cholmod_start(&common); }
  ~Impl() {
    if (L != nullptr) cholmod_free_factor(&L, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  const int* super() const { return static_cast<const int*>(L->super); }
  const int* pi() const { return static_cast<const int*>(L->pi); }
  const int* px() const { return static_cast<const int*>(L->px); }
  const int* rows() const { return static_cast<const int*>(L->s); }

  /// Offset into sigma of permuted entry (i, j), or -1 if not in the pattern.
  std::ptrdiff_t offset(int i, int j) const {
    if (i < j) std::swap(i, j);
    const int s = col_super[static_cast<size_t>(j)];
    const int* first = rows() + pi()[s];
    const int* last = rows() + pi()[s + 1];
    const int* it = std::lower_bound(first, last, i);
    if (it == last || *it != i) return -1;
    const std::ptrdiff_t nrows = last - first;
    return px()[s] + static_cast<std::ptrdiff_t>(j - super()[s]) * nrows + (it - first);
  }

  void factor(const Eigen::SparseMatrix<double>& Lambda, MarginalsOrdering ordering);
  void factor_in_cholmod_ordering(const Eigen::SparseMatrix<double>& Lambda);
  void factor_permuted(const Eigen::SparseMatrix<double>& Lambda, MarginalsOrdering ordering);
  void invert();
  /// X = Lambda⁻¹ B (n x m, any strides) by a forward and a backward supernodal triangular
  /// solve with L (exact_marginals_solve.cpp). Uses the workspace above.
  void solve(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X) const;
  /// The forward half: solve_work = Y with L Y = P B (n x m, row-major).
  void forward(const Eigen::Ref<const Eigen::MatrixXd>& B) const;
};

}  // namespace nav::core

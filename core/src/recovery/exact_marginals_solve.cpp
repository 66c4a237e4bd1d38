// Solves with the supernodal factor of ExactMarginals (recovery/exact_marginals.h): Λ X = B as
// P Λ Pᵀ = L Lᵀ, a forward solve L Y = P B and a backward solve Lᵀ Z = Y, X = Pᵀ Z (the
// quadratic form Bᵀ Λ⁻¹ B = YᵀY needs the forward solve only), one
// supernode at a time (the supernodal triangular solves of CHOLMOD's cholmod_super_lsolve /
// ltsolve; Ng & Peyton, SIAM J. Sci. Comput. 1993). The right-hand sides are kept row-major
// so that the scattered rows of a supernode are contiguous; the dense part of each supernode
// runs in Eigen (selinv_kernel.inc, AVX2+FMA where the CPU has it) instead of the BLAS that
// CHOLMOD calls with a few columns, where ATLAS falls back to its reference trsm.
#include <string>

#include "exact_marginals_impl.h"
#include "selinv_kernel.h"

namespace nav::core {

void ExactMarginals::Impl::forward(const Eigen::Ref<const Eigen::MatrixXd>& B) const {
  const auto m = static_cast<int>(B.cols());
  const SupernodeSolveKernels kernels =
      supernode_solve_kernels(kernel == MarginalsKernel::kBaseline);
  const int* Perm = perm.data();
  const auto* Lx = static_cast<const double*>(L->x);
  const int nsuper = static_cast<int>(L->nsuper);
  RowMajorMatrix& W = solve_work;
  RowMajorMatrix& T = solve_rows;
  W.resize(n, m);
  T.resize(std::max<Eigen::Index>(static_cast<Eigen::Index>(L->maxesize), 1), m);
  for (int k = 0; k < n; ++k) W.row(k) = B.row(Perm[k]);
  for (int s = 0; s < nsuper; ++s) {  // L Y = P B
    const int k1 = super()[s], nc = super()[s + 1] - k1, nrows = pi()[s + 1] - pi()[s];
    const int* R = rows() + pi()[s] + nc;
    kernels.lsolve(Lx + px()[s], nrows, nc, W.row(k1).data(), m, T.data());
    for (int p = 0; p < nrows - nc; ++p) W.row(R[p]) -= T.row(p);
  }
}

void ExactMarginals::Impl::solve(const Eigen::Ref<const Eigen::MatrixXd>& B,
                                 Eigen::Ref<Eigen::MatrixXd> X) const {
  forward(B);
  const auto m = static_cast<int>(B.cols());
  const SupernodeSolveKernels kernels =
      supernode_solve_kernels(kernel == MarginalsKernel::kBaseline);
  const auto* Lx = static_cast<const double*>(L->x);
  RowMajorMatrix& W = solve_work;
  RowMajorMatrix& T = solve_rows;
  for (int s = static_cast<int>(L->nsuper) - 1; s >= 0; --s) {  // Lᵀ Z = Y
    const int k1 = super()[s], nc = super()[s + 1] - k1, nrows = pi()[s + 1] - pi()[s];
    const int* R = rows() + pi()[s] + nc;
    for (int p = 0; p < nrows - nc; ++p) T.row(p) = W.row(R[p]);
    kernels.ltsolve(Lx + px()[s], nrows, nc, W.row(k1).data(), m, T.data());
  }
  for (int k = 0; k < n; ++k) X.row(perm[k]) = W.row(k);
}

void ExactMarginals::solve(const Eigen::Ref<const Eigen::MatrixXd>& B,
                           Eigen::Ref<Eigen::MatrixXd> X) const {
  if (B.rows() != impl_->n || X.rows() != impl_->n || X.cols() != B.cols()) {
    throw ExactMarginalsError("ExactMarginals::solve: factor of dimension " +
                              std::to_string(impl_->n) + ", B " + std::to_string(B.rows()) + "x" +
                              std::to_string(B.cols()) + ", X " + std::to_string(X.rows()) + "x" +
                              std::to_string(X.cols()));
  }
  if (B.cols() == 0) return;
  impl_->solve(B, X);
}

Eigen::MatrixXd ExactMarginals::quadratic_form(const Eigen::Ref<const Eigen::MatrixXd>& B) const {
  if (B.rows() != impl_->n) {
    throw ExactMarginalsError("ExactMarginals::quadratic_form: factor of dimension " +
                              std::to_string(impl_->n) + ", B " + std::to_string(B.rows()) + "x" +
                              std::to_string(B.cols()));
  }
  if (B.cols() == 0) return Eigen::MatrixXd(0, 0);
  impl_->forward(B);  // Bᵀ Λ⁻¹ B = Bᵀ Pᵀ L⁻ᵀ L⁻¹ P B = YᵀY with L Y = P B
  const auto& Y = impl_->solve_work;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(B.cols(), B.cols());
  gram.selfadjointView<Eigen::Lower>().rankUpdate(Y.transpose());
  return gram.selfadjointView<Eigen::Lower>();
}

}  // namespace nav::core

#pragma once
// A CHOLMOD header over an Eigen matrix's storage, shared by the recovery's CHOLMOD users
// (exact_marginals.cpp, kept_equal_factor.cpp). Internal to nav_core.
#include <cholmod.h>

#include <Eigen/SparseCore>

namespace nav::core::detail {

/// The lower triangle stored in C as a symmetric CHOLMOD matrix (stype -1), no copy: C must
/// outlive it. `sorted`: C's row indices are sorted within each column (Eigen's symmetric
/// permutation leaves them in scatter order, which CHOLMOD's analysis and factorisation accept).
inline cholmod_sparse lower_view(Eigen::SparseMatrix<double>& C, bool sorted) {
  cholmod_sparse A{};
  A.nrow = A.ncol = static_cast<size_t>(C.rows());
  A.nzmax = static_cast<size_t>(C.nonZeros());
  A.p = C.outerIndexPtr();
  A.i = C.innerIndexPtr();
  A.x = C.valuePtr();
  A.stype = -1;
  A.itype = CHOLMOD_INT;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = sorted ? 1 : 0;
  A.packed = 1;
  return A;
}

}  // namespace nav::core::detail

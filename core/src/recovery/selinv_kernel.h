#pragma once
// Runtime-dispatched dense kernels of the supernodal factor (selinv_kernel.inc): the selected
// inversion (exact_marginals.cpp) and the two triangular solves (exact_marginals_solve.cpp).
// Private to core/src/recovery; plain pointers only, so the AVX2 copy's renamed Eigen never
// crosses the interface.

namespace nav::core {

/// One supernode s of the selected inverse: from its factor block L_block (nrows x nc,
/// column-major, leading dimension nrows; its nc columns' diagonal block on top) and the
/// already gathered lower triangle of Sigma_RR (nr x nr, nr = nrows - nc, leading dimension
/// ld_srr), writes Sigma's nrows x nc block of s to S_block (same layout as L_block; the
/// diagonal block in full).
using SelinvSupernodeKernel = void (*)(const double* L_block, int nrows, int nc,
                                       double* S_block, double* S_RR, int ld_srr);

/// One supernode of the forward solve L Y = B, m right-hand sides: solves L_JJ X_J = X_J in
/// place (X_J: the supernode's nc rows, nc x m, row-major) and writes T = L_RJ X_J (nr x m,
/// row-major), which the caller subtracts from the rows R.
using LsolveSupernodeKernel = void (*)(const double* L_block, int nrows, int nc, double* X_J,
                                       int m, double* T);
/// One supernode of the backward solve Lᵀ Z = Y: X_J -= L_RJᵀ X_R (X_R: the rows R gathered,
/// nr x m, row-major), then solves L_JJᵀ X_J = X_J in place.
using LtsolveSupernodeKernel = void (*)(const double* L_block, int nrows, int nc, double* X_J,
                                        int m, const double* X_R);

namespace baseline {
void selinv_supernode(const double* L_block, int nrows, int nc, double* S_block, double* S_RR,
                      int ld_srr);
void lsolve_supernode(const double* L_block, int nrows, int nc, double* X_J, int m, double* T);
void ltsolve_supernode(const double* L_block, int nrows, int nc, double* X_J, int m,
                       const double* X_R);
}  // namespace baseline
/// Compiled with -mavx2 -mfma (x86-64 only; call only when the CPU has both).
namespace avx2 {
void selinv_supernode(const double* L_block, int nrows, int nc, double* S_block, double* S_RR,
                      int ld_srr);
void lsolve_supernode(const double* L_block, int nrows, int nc, double* X_J, int m, double* T);
void ltsolve_supernode(const double* L_block, int nrows, int nc, double* X_J, int m,
                       const double* X_R);
}  // namespace avx2

struct SupernodeSolveKernels {
  LsolveSupernodeKernel lsolve;
  LtsolveSupernodeKernel ltsolve;
};

/// The AVX2+FMA kernels when this CPU has both (and they were compiled) and `baseline_only` is
/// false, else the baseline ones. The CPU check runs once per process.
SelinvSupernodeKernel selinv_supernode_kernel(bool baseline_only);
SupernodeSolveKernels supernode_solve_kernels(bool baseline_only);
/// "avx2-fma" or "baseline": what selinv_supernode_kernel(false) returns here.
const char* selinv_kernel_name();

}  // namespace nav::core

#pragma once
// Runtime-dispatched dense kernel of the supernodal selected inversion (exact_marginals.cpp,
// selinv_kernel.inc). Private to core/src/recovery; plain pointers only, so the AVX2 copy's
// renamed Eigen never crosses the interface.

namespace nav::core {

/// One supernode s of the selected inverse: from its factor block L_block (nrows x nc,
/// column-major, leading dimension nrows; its nc columns' diagonal block on top) and the
/// already gathered lower triangle of Sigma_RR (nr x nr, nr = nrows - nc, leading dimension
/// ld_srr), writes Sigma's nrows x nc block of s to S_block (same layout as L_block; the
/// diagonal block in full).
using SelinvSupernodeKernel = void (*)(const double* L_block, int nrows, int nc,
                                       double* S_block, double* S_RR, int ld_srr);

namespace baseline {
void selinv_supernode(const double* L_block, int nrows, int nc, double* S_block, double* S_RR,
                      int ld_srr);
}
namespace avx2 {
/// Compiled with -mavx2 -mfma (x86-64 only; call only when the CPU has both).
void selinv_supernode(const double* L_block, int nrows, int nc, double* S_block, double* S_RR,
                      int ld_srr);
}

/// The AVX2+FMA kernel when this CPU has both (and it was compiled), else the baseline one.
/// Chosen once per process.
SelinvSupernodeKernel selinv_supernode_kernel();
/// "avx2-fma" or "baseline": what selinv_supernode_kernel() returns here.
const char* selinv_kernel_name();

}  // namespace nav::core

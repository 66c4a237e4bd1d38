// The supernode kernels (selinv_kernel.inc) with the project's default instruction set, and the
// load-time choice between them and the AVX2+FMA copy.
#define NAV_SELINV_NAMESPACE baseline
#include "selinv_kernel.inc"

namespace nav::core {
namespace {

bool cpu_has_avx2_fma() {
#if defined(NAV_SELINV_HAVE_AVX2) && (defined(__x86_64__) || defined(__i386__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

const bool kUseAvx2 = cpu_has_avx2_fma();

}  // namespace

SelinvSupernodeKernel selinv_supernode_kernel(bool baseline_only) {
#if defined(NAV_SELINV_HAVE_AVX2)
  if (kUseAvx2 && !baseline_only) return &avx2::selinv_supernode;
#endif
  return &baseline::selinv_supernode;
}

SupernodeSolveKernels supernode_solve_kernels(bool baseline_only) {
#if defined(NAV_SELINV_HAVE_AVX2)
  if (kUseAvx2 && !baseline_only) return {&avx2::lsolve_supernode, &avx2::ltsolve_supernode};
#endif
  return {&baseline::lsolve_supernode, &baseline::ltsolve_supernode};
}

const char* selinv_kernel_name() { return kUseAvx2 ? "avx2-fma" : "baseline"; }

}  // namespace nav::core

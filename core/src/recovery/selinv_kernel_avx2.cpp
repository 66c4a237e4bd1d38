// The selected-inversion supernode kernel (selinv_kernel.inc) compiled with -mavx2 -mfma
// (core/CMakeLists.txt), so Eigen's GEMM and triangular kernels use 256-bit FMA packets.
// Eigen's namespace is renamed in this translation unit: its inline templates get distinct
// symbols and the linker cannot merge an AVX2 instantiation into the baseline code (or the
// reverse). Only called after a CPU check (selinv_kernel_baseline.cpp).
#if defined(NAV_SELINV_HAVE_AVX2)
#define Eigen nav_selinv_avx2_eigen
#define NAV_SELINV_NAMESPACE avx2
#include "selinv_kernel.inc"
#endif

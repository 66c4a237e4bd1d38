// Row-major triangular solves with a simplicial LDLᵀ factor (recovery/ldl_solve.h).
#include "ldl_solve.h"

#include <cstddef>

namespace nav::core::detail {
namespace {

// 4-lane generic vectors, as the packed PCG's kernels (packed_pcg.cpp: 4 lanes lower well on
// AVX2 and map onto NEON elsewhere); on x86-64 each pass is compiled for x86-64-v4, v3 and the
// baseline and chosen at load time.
typedef double v4d __attribute__((vector_size(32)));
typedef double v4d_unaligned __attribute__((vector_size(32), aligned(8), may_alias));
#define NAV_LOAD(p) (*reinterpret_cast<const v4d_unaligned*>(p))
#define NAV_STORE(p, v) (*reinterpret_cast<v4d_unaligned*>(p) = (v))
#if defined(__x86_64__)
#define NAV_LDL_KERNEL __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define NAV_LDL_KERNEL
#endif

constexpr int kLanes = 4;
constexpr int kMaxChunks = 4;  // 16 columns per pass: 4 accumulators, loads of one 128-byte row

/// Forward and diagonal passes over C chunks of 4 columns starting at Y (row stride `stride`).
template <int C>
[[gnu::always_inline]] inline void forward_chunks(const SimplicialLdl& L, double* Y,
                                                  std::ptrdiff_t stride) {
  for (int j = 0; j < L.n; ++j) {
    double* yj = Y + j * stride;
    v4d y[C];
    for (int c = 0; c < C; ++c) y[c] = NAV_LOAD(yj + c * kLanes);
    const int end = L.p[j] + L.nz[j];
    for (int k = L.p[j] + 1; k < end; ++k) {
      const double l = L.value[k];
      double* yi = Y + L.row[k] * stride;
      for (int c = 0; c < C; ++c) NAV_STORE(yi + c * kLanes, NAV_LOAD(yi + c * kLanes) - l * y[c]);
    }
    // Row j is final once the columns before it were scattered: scale it by D_j⁻¹ now.
    const double inverse_pivot = 1.0 / L.value[L.p[j]];
    for (int c = 0; c < C; ++c) NAV_STORE(yj + c * kLanes, inverse_pivot * y[c]);
  }
}

/// Backward pass over C chunks of 4 columns: row j gathers the rows below it in column j.
template <int C>
[[gnu::always_inline]] inline void backward_chunks(const SimplicialLdl& L, double* Y,
                                                   std::ptrdiff_t stride) {
  for (int j = L.n - 1; j >= 0; --j) {
    double* yj = Y + j * stride;
    v4d acc[C];
    for (int c = 0; c < C; ++c) acc[c] = NAV_LOAD(yj + c * kLanes);
    const int end = L.p[j] + L.nz[j];
    for (int k = L.p[j] + 1; k < end; ++k) {
      const double l = L.value[k];
      const double* yi = Y + L.row[k] * stride;
      for (int c = 0; c < C; ++c) acc[c] -= l * NAV_LOAD(yi + c * kLanes);
    }
    for (int c = 0; c < C; ++c) NAV_STORE(yj + c * kLanes, acc[c]);
  }
}

NAV_LDL_KERNEL void forward_one(const SimplicialLdl& L, double* y) {
  for (int j = 0; j < L.n; ++j) {
    const double yj = y[j];
    if (yj == 0.0) continue;  // a sparse r: only the columns of its reach are read
    const int end = L.p[j] + L.nz[j];
    for (int k = L.p[j] + 1; k < end; ++k) y[L.row[k]] -= L.value[k] * yj;
    y[j] = yj / L.value[L.p[j]];
  }
}

NAV_LDL_KERNEL void backward_one(const SimplicialLdl& L, double* y) {
  for (int j = L.n - 1; j >= 0; --j) {
    double acc = y[j];
    const int end = L.p[j] + L.nz[j];
    for (int k = L.p[j] + 1; k < end; ++k) acc -= L.value[k] * y[L.row[k]];
    y[j] = acc;
  }
}

NAV_LDL_KERNEL void forward_vectors(const SimplicialLdl& L, double* Y, std::ptrdiff_t stride,
                                    int chunks) {
  switch (chunks) {
    case 1:
      forward_chunks<1>(L, Y, stride);
      break;
    case 2:
      forward_chunks<2>(L, Y, stride);
      break;
    case 3:
      forward_chunks<3>(L, Y, stride);
      break;
    default:
      forward_chunks<4>(L, Y, stride);
      break;
  }
}

NAV_LDL_KERNEL void backward_vectors(const SimplicialLdl& L, double* Y, std::ptrdiff_t stride,
                                     int chunks) {
  switch (chunks) {
    case 1:
      backward_chunks<1>(L, Y, stride);
      break;
    case 2:
      backward_chunks<2>(L, Y, stride);
      break;
    case 3:
      backward_chunks<3>(L, Y, stride);
      break;
    default:
      backward_chunks<4>(L, Y, stride);
      break;
  }
}

}  // namespace

int ldl_width(int columns) { return columns <= 1 ? 1 : (columns + kLanes - 1) / kLanes * kLanes; }

void ldl_forward_diagonal(const SimplicialLdl& L, double* Y, int width, int columns) {
  if (width == 1) {
    forward_one(L, Y);
    return;
  }
  // More than 16 columns: passes over groups of up to 16 (4 accumulators per row).
  const int lanes = (columns + kLanes - 1) / kLanes * kLanes;
  const int used = lanes < width ? lanes : width;
  for (int offset = 0; offset < used; offset += kMaxChunks * kLanes) {
    const int chunks = (used - offset) / kLanes;
    forward_vectors(L, Y + offset, width, chunks < kMaxChunks ? chunks : kMaxChunks);
  }
}

void ldl_backward(const SimplicialLdl& L, double* Y, int width) {
  if (width == 1) {
    backward_one(L, Y);
    return;
  }
  for (int offset = 0; offset < width; offset += kMaxChunks * kLanes) {
    const int chunks = (width - offset) / kLanes;
    backward_vectors(L, Y + offset, width, chunks < kMaxChunks ? chunks : kMaxChunks);
  }
}

}  // namespace nav::core::detail

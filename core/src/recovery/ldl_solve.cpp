// Row-major triangular solves with a simplicial LDLᵀ factor (recovery/ldl_solve.h).
#include "ldl_solve.h"

#include <cstddef>
#include <cstring>

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
constexpr int kMaxBlockDim = 12;  // the largest state block (InformationMatrix::kMaxBlockDim)

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

/// Row j of the backward pass over C chunks of 4 columns: it gathers the rows of column j's
/// entries L.p[j]+1 .. end-1.
template <int C>
[[gnu::always_inline]] inline void backward_entries(const SimplicialLdl& L, int j, int end,
                                                    double* Y, std::ptrdiff_t stride) {
  double* yj = Y + j * stride;
  v4d acc[C];
  for (int c = 0; c < C; ++c) acc[c] = NAV_LOAD(yj + c * kLanes);
  for (int k = L.p[j] + 1; k < end; ++k) {
    const double l = L.value[k];
    const double* yi = Y + L.row[k] * stride;
    for (int c = 0; c < C; ++c) acc[c] -= l * NAV_LOAD(yi + c * kLanes);
  }
  for (int c = 0; c < C; ++c) NAV_STORE(yj + c * kLanes, acc[c]);
}

/// Row j of the backward pass: it gathers the rows below it in column j.
template <int C>
[[gnu::always_inline]] inline void backward_column(const SimplicialLdl& L, int j, double* Y,
                                                   std::ptrdiff_t stride) {
  backward_entries<C>(L, j, L.p[j] + L.nz[j], Y, stride);
}

/// The backward pass column by column.
template <int C>
[[gnu::always_inline]] inline void backward_chunks(const SimplicialLdl& L, double* Y,
                                                   std::ptrdiff_t stride) {
  for (int j = L.n - 1; j >= 0; --j) backward_column<C>(L, j, Y, stride);
}

/// Block b's d columns j0 = b·d .. j0+d-1 as one supernode: each column c holds its diagonal,
/// then the rows j0+c+1 .. j0+d-1 of the block in order, then the same off-block rows as every
/// other column of the block (`rows`, m of them; `values[c]` its entries there). What the
/// factor of a block matrix holds when no modification left a column with a pattern of its own.
struct BlockColumns {
  int m = 0;
  const int* rows = nullptr;
  const double* values[kMaxBlockDim] = {};
};

bool block_columns(const SimplicialLdl& L, int j0, int d, BlockColumns& block) {
  const int first_off = L.p[j0] + d;  // column 0: diagonal, d-1 rows of the block, then the rest
  block.m = L.nz[j0] - d;
  if (block.m < 0) return false;
  block.rows = L.row + first_off;
  for (int c = 0; c < d; ++c) {
    const int j = j0 + c, p = L.p[j];
    if (L.nz[j] != block.m + d - c) return false;
    for (int t = 1; t < d - c; ++t) {
      if (L.row[p + t] != j + t) return false;
    }
    const int* rows = L.row + p + d - c;
    if (c > 0 && std::memcmp(rows, block.rows, sizeof(int) * static_cast<size_t>(block.m)) != 0)
      return false;
    block.values[c] = L.value + p + d - c;
  }
  return true;
}

/// Backward pass of the block's columns G at a time (G·C accumulators in registers): every row
/// below the block is gathered once per G columns instead of once per column, from L1 after
/// the first group. Then the block's own triangle, from its last column up.
template <int G, int C>
[[gnu::always_inline]] inline void backward_block(const SimplicialLdl& L, const BlockColumns& B,
                                                  int j0, int d, double* Y, std::ptrdiff_t stride) {
  for (int c0 = 0; c0 < d; c0 += G) {
    v4d acc[G][C];
    for (int g = 0; g < G; ++g)
      for (int c = 0; c < C; ++c) acc[g][c] = NAV_LOAD(Y + (j0 + c0 + g) * stride + c * kLanes);
    for (int i = 0; i < B.m; ++i) {
      const double* yi = Y + B.rows[i] * stride;
      v4d y[C];
      for (int c = 0; c < C; ++c) y[c] = NAV_LOAD(yi + c * kLanes);
      for (int g = 0; g < G; ++g) {
        const double l = B.values[c0 + g][i];
        for (int c = 0; c < C; ++c) acc[g][c] -= l * y[c];
      }
    }
    for (int g = 0; g < G; ++g)
      for (int c = 0; c < C; ++c) NAV_STORE(Y + (j0 + c0 + g) * stride + c * kLanes, acc[g][c]);
  }
  // Column col's entries in the block come first (block_columns checked their rows).
  for (int col = d - 2; col >= 0; --col) {
    const int j = j0 + col;
    backward_entries<C>(L, j, L.p[j] + d - col, Y, stride);
  }
}

/// The backward pass block by block (d | L.n): a block of supernode pattern (block_columns)
/// by backward_block, any other column by column. Returns the blocks taken as supernodes.
template <int C>
[[gnu::always_inline]] inline int backward_blocks(const SimplicialLdl& L, int d, double* Y,
                                                  std::ptrdiff_t stride) {
  int supernodes = 0;
  BlockColumns block;
  for (int j0 = L.n - d; j0 >= 0; j0 -= d) {
    if (d % 3 == 0 && block_columns(L, j0, d, block)) {
      backward_block<3, C>(L, block, j0, d, Y, stride);
      ++supernodes;
      continue;
    }
    for (int j = j0 + d - 1; j >= j0; --j) backward_column<C>(L, j, Y, stride);
  }
  return supernodes;
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

NAV_LDL_KERNEL int backward_block_vectors(const SimplicialLdl& L, int d, double* Y,
                                          std::ptrdiff_t stride, int chunks) {
  switch (chunks) {
    case 1:
      return backward_blocks<1>(L, d, Y, stride);
    case 2:
      return backward_blocks<2>(L, d, Y, stride);
    case 3:
      return backward_blocks<3>(L, d, Y, stride);
    default:
      return backward_blocks<4>(L, d, Y, stride);
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

int ldl_backward_blocks(const SimplicialLdl& L, int block_dim, double* Y, int width) {
  if (width == 1 || block_dim > kMaxBlockDim || L.n % block_dim != 0) {
    ldl_backward(L, Y, width);
    return 0;
  }
  int supernodes = 0;
  for (int offset = 0; offset < width; offset += kMaxChunks * kLanes) {
    const int chunks = (width - offset) / kLanes;
    supernodes = backward_block_vectors(L, block_dim, Y + offset, width,
                                        chunks < kMaxChunks ? chunks : kMaxChunks);
  }
  return supernodes;
}

}  // namespace nav::core::detail

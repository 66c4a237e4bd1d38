// Packed multi-RHS PCG on the filter's block matrix (see recovery/packed_pcg.h).
#include "nav/core/recovery/packed_pcg.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

namespace nav::core {
namespace {

// 4 doubles: one AVX2 register (half an AVX-512, two SSE2 registers in the other clones). GCC
// lowers wider generic vectors on AVX2 through the stack, and a tile kernel keeps d of them
// live: 4 lanes keep d = 12 in 12 + 2 of the 16 AVX2 registers (8 lanes were 5x slower at
// d = 12 and 1.4x at d = 6, 10x in the Gram kernel; docs/performance.md). Packed widths stay
// multiples of 8 (packed_width).
typedef double v4d __attribute__((vector_size(32)));
constexpr int kLanes = 4;
constexpr int kWidthMultiple = 8;

// On x86-64 each hot loop is compiled three times and the best one for the CPU is chosen at
// load time (GNU ifunc). The project builds for baseline x86-64, so without this the kernels
// would be limited to SSE2. Elsewhere (aarch64, armhf) the generic vectors map onto the
// target's own SIMD (NEON) with one version.
#if defined(__x86_64__)
#define NAV_PACKED_KERNEL \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define NAV_PACKED_KERNEL
#endif

// Unaligned, aliasing access to 4 doubles. Macros, not functions: returning a vector type by
// value from a function compiled for the baseline ISA would change the ABI (-Wpsabi).
typedef double v4d_unaligned __attribute__((vector_size(32), aligned(8), may_alias));
#define NAV_LOAD(p) (*reinterpret_cast<const v4d_unaligned*>(p))
#define NAV_STORE(p, v) (*reinterpret_cast<v4d_unaligned*>(p) = (v))

/// Asks for block row i's stored blocks (64-byte lines) while the row before is computed: the
/// blocks are separate allocations. Only for d <= 6: a 6 x 6 block is 4.5 lines, too short
/// for the hardware prefetcher to follow, and asking made BM_MultiplyPacked 1.3-1.6x faster;
/// a 12 x 12 block is 18 consecutive lines, which it follows (no gain at d = 12).
[[gnu::always_inline]] inline void prefetch_row(int d, const int* row_start,
                                                const double* const* data, int i) {
  constexpr int kLineDoubles = 8;
  for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
    for (int e = 0; e < d * d; e += kLineDoubles) __builtin_prefetch(data[k] + e);
  }
}

/// Y_i = Σ_k A_{i,col[k]} X_{col[k]} for every block row i (tile kernel, see the header),
/// optionally dots += Σ_rows X ∘ Y. D = 0: block size d at run time.
template <int D>
[[gnu::always_inline]] inline void multiply_rows(int d_runtime, const int* row_start,
                                                 const int* col, const double* const* data,
                                                 int rows, const double* X, double* Y, int width,
                                                 double* dots) {
  const int d = D > 0 ? D : d_runtime;
  constexpr int kMax = D > 0 ? D : InformationMatrix::kMaxBlockDim;
  const std::ptrdiff_t row_stride = std::ptrdiff_t{d} * width;
  for (int i = 0; i < rows; ++i) {
    if (D > 0 && D <= 6 && i + 1 < rows) prefetch_row(d, row_start, data, i + 1);
    for (int ch = 0; ch < width; ch += kLanes) {
      v4d acc[kMax];
      for (int r = 0; r < d; ++r) acc[r] = v4d{};
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
        const double* a = data[k];
        const double* x = X + col[k] * row_stride + ch;
        for (int q = 0; q < d; ++q) {
          const v4d xq = NAV_LOAD(x + std::ptrdiff_t{q} * width);
          for (int r = 0; r < d; ++r) acc[r] += a[q * d + r] * xq;
        }
      }
      double* y = Y + i * row_stride + ch;
      for (int r = 0; r < d; ++r) NAV_STORE(y + std::ptrdiff_t{r} * width, acc[r]);
      if (dots != nullptr) {
        const double* xi = X + i * row_stride + ch;
        v4d s = NAV_LOAD(dots + ch);
        for (int r = 0; r < d; ++r) s += NAV_LOAD(xi + std::ptrdiff_t{r} * width) * acc[r];
        NAV_STORE(dots + ch, s);
      }
    }
  }
}

NAV_PACKED_KERNEL
void multiply_kernel(int d, const int* row_start, const int* col, const double* const* data,
                     int rows, const double* X, double* Y, int width, double* dots) {
  switch (d) {
    case 6:
      return multiply_rows<6>(d, row_start, col, data, rows, X, Y, width, dots);
    case 12:
      return multiply_rows<12>(d, row_start, col, data, rows, X, Y, width, dots);
    default:
      return multiply_rows<0>(d, row_start, col, data, rows, X, Y, width, dots);
  }
}

/// Z_i = Minv_i R_i for every block (inverses stored contiguously), dots += Σ R ∘ Z.
template <int D>
[[gnu::always_inline]] inline void block_diagonal_rows(int d_runtime, const double* inverse,
                                                       int rows, const double* R, double* Z,
                                                       int width, double* dots) {
  const int d = D > 0 ? D : d_runtime;
  constexpr int kMax = D > 0 ? D : InformationMatrix::kMaxBlockDim;
  const std::ptrdiff_t row_stride = std::ptrdiff_t{d} * width;
  for (int i = 0; i < rows; ++i) {
    const double* a = inverse + std::ptrdiff_t{i} * d * d;
    const double* r_i = R + i * row_stride;
    double* z_i = Z + i * row_stride;
    for (int ch = 0; ch < width; ch += kLanes) {
      v4d acc[kMax];
      for (int r = 0; r < d; ++r) acc[r] = v4d{};
      for (int q = 0; q < d; ++q) {
        const v4d rq = NAV_LOAD(r_i + std::ptrdiff_t{q} * width + ch);
        for (int r = 0; r < d; ++r) acc[r] += a[q * d + r] * rq;
      }
      for (int r = 0; r < d; ++r) NAV_STORE(z_i + std::ptrdiff_t{r} * width + ch, acc[r]);
      if (dots != nullptr) {
        v4d s = NAV_LOAD(dots + ch);
        for (int r = 0; r < d; ++r) {
          s += NAV_LOAD(r_i + std::ptrdiff_t{r} * width + ch) * acc[r];
        }
        NAV_STORE(dots + ch, s);
      }
    }
  }
}

NAV_PACKED_KERNEL
void block_diagonal_kernel(int d, const double* inverse, int rows, const double* R, double* Z,
                           int width, double* dots) {
  switch (d) {
    case 6:
      return block_diagonal_rows<6>(d, inverse, rows, R, Z, width, dots);
    case 12:
      return block_diagonal_rows<12>(d, inverse, rows, R, Z, width, dots);
    default:
      return block_diagonal_rows<0>(d, inverse, rows, R, Z, width, dots);
  }
}

/// dots[c] = Σ_rows A ∘ B (rows x width packed).
NAV_PACKED_KERNEL
void column_dots(const double* A, const double* B, std::ptrdiff_t rows, int width, double* dots) {
  for (int ch = 0; ch < width; ch += kLanes) {
    v4d s{};
    for (std::ptrdiff_t i = 0; i < rows; ++i) {
      s += NAV_LOAD(A + i * width + ch) * NAV_LOAD(B + i * width + ch);
    }
    NAV_STORE(dots + ch, s);
  }
}

/// gram (width x width, row-major) = Aᵀ A over the rows of a packed matrix. Row chunks that stay
/// in L1 (4 KB at width 16): A is read from memory once, not once per column. Each entry sums
/// the rows in order, as an unchunked loop would.
NAV_PACKED_KERNEL
void gram_kernel(const double* A, std::ptrdiff_t rows, int width, double* gram) {
  constexpr std::ptrdiff_t kChunkRows = 32;
  std::fill(gram, gram + std::ptrdiff_t{width} * width, 0.0);
  for (std::ptrdiff_t first = 0; first < rows; first += kChunkRows) {
    const std::ptrdiff_t last = std::min(rows, first + kChunkRows);
    for (int c = 0; c < width; ++c) {
      for (int ch = 0; ch < width; ch += kLanes) {
        v4d s = NAV_LOAD(gram + std::ptrdiff_t{c} * width + ch);
        for (std::ptrdiff_t i = first; i < last; ++i) {
          s += A[i * width + c] * NAV_LOAD(A + i * width + ch);
        }
        NAV_STORE(gram + std::ptrdiff_t{c} * width + ch, s);
      }
    }
  }
}

/// R = B - Q.
NAV_PACKED_KERNEL
void subtract(const double* B, const double* Q, double* R, std::ptrdiff_t size) {
  for (std::ptrdiff_t k = 0; k < size; ++k) R[k] = B[k] - Q[k];
}

/// X += α ∘ P, R -= α ∘ Q (α per packed column), rr = Σ_rows R ∘ R.
NAV_PACKED_KERNEL
void step_x_r(double* X, double* R, const double* P, const double* Q, const double* alpha,
              std::ptrdiff_t rows, int width, double* rr) {
  for (int ch = 0; ch < width; ch += kLanes) {
    const v4d a = NAV_LOAD(alpha + ch);
    v4d s{};
    for (std::ptrdiff_t i = 0; i < rows; ++i) {
      const std::ptrdiff_t k = i * width + ch;
      NAV_STORE(X + k, NAV_LOAD(X + k) + a * NAV_LOAD(P + k));
      const v4d r = NAV_LOAD(R + k) - a * NAV_LOAD(Q + k);
      NAV_STORE(R + k, r);
      s += r * r;
    }
    NAV_STORE(rr + ch, s);
  }
}

/// P = Z + β ∘ P.
NAV_PACKED_KERNEL
void update_direction(double* P, const double* Z, const double* beta, std::ptrdiff_t rows,
                      int width) {
  for (int ch = 0; ch < width; ch += kLanes) {
    const v4d b = NAV_LOAD(beta + ch);
    for (std::ptrdiff_t i = 0; i < rows; ++i) {
      const std::ptrdiff_t k = i * width + ch;
      NAV_STORE(P + k, NAV_LOAD(Z + k) + b * NAV_LOAD(P + k));
    }
  }
}

/// Capacity for `size` elements, growing by at least 1.5x: a filter that grows by one state per
/// step reallocates O(log n) times, not every step.
void reserve_growing(std::vector<double>& v, size_t size) {
  if (v.capacity() < size) v.reserve(std::max(size, v.capacity() + v.capacity() / 2));
}

double* scratch(std::vector<double>& v, std::ptrdiff_t size) {
  if (static_cast<std::ptrdiff_t>(v.size()) < size) v.resize(static_cast<size_t>(size));
  return v.data();
}

double relative(double residual, double rhs) { return rhs > 0.0 ? residual / rhs : residual; }

}  // namespace

int packed_width(int columns) {
  return (std::max(columns, 1) + kWidthMultiple - 1) / kWidthMultiple * kWidthMultiple;
}

void pack_columns(const Eigen::Ref<const Eigen::MatrixXd>& M, int width,
                  std::vector<double>* packed) {
  const Eigen::Index n = M.rows();
  reserve_growing(*packed, static_cast<size_t>(n * width));
  packed->assign(static_cast<size_t>(n * width), 0.0);
  double* out = packed->data();
  for (Eigen::Index c = 0; c < M.cols(); ++c) {
    const double* in = M.col(c).data();
    for (Eigen::Index i = 0; i < n; ++i) out[i * width + c] = in[i];
  }
}

void unpack_columns(const std::vector<double>& packed, int width, Eigen::Ref<Eigen::MatrixXd> M) {
  const Eigen::Index n = M.rows();
  const double* in = packed.data();
  for (Eigen::Index c = 0; c < M.cols(); ++c) {
    double* out = M.col(c).data();
    for (Eigen::Index i = 0; i < n; ++i) out[i] = in[i * width + c];
  }
}

void PackedSpdOperator::multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                 Eigen::Ref<Eigen::MatrixXd> Y) const {
  const int width = packed_width(static_cast<int>(X.cols()));
  pack_columns(X, width, &x_);
  reserve_growing(y_, x_.size());
  y_.resize(x_.size());
  A_.multiply(x_.data(), y_.data(), width);
  unpack_columns(y_, width, Y);
}

Eigen::MatrixXd packed_gram(const double* A, Eigen::Index rows, int width, int first,
                            int count) {
  std::vector<double> gram(static_cast<size_t>(width) * static_cast<size_t>(width));
  gram_kernel(A, rows, width, gram.data());
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
      G(gram.data(), width, width);
  return G.block(first, first, count, count);
}

void PackedBlockOperator::refresh(const InformationMatrix& lambda) {
  block_dim_ = lambda.block_dim();
  const int blocks = lambda.num_blocks();
  row_start_.resize(static_cast<size_t>(blocks) + 1);
  col_.clear();
  data_.clear();
  row_start_[0] = 0;
  for (int i = 0; i < blocks; ++i) {
    col_.push_back(i);
    data_.push_back(lambda.diagonal_block(i).data());
    const int neighbours = lambda.num_neighbours(i);
    for (int k = 0; k < neighbours; ++k) {
      col_.push_back(lambda.neighbour(i, k));
      data_.push_back(lambda.neighbour_block(i, k).data());
    }
    row_start_[static_cast<size_t>(i) + 1] = static_cast<int>(col_.size());
  }
}

void PackedBlockOperator::multiply(const double* X, double* Y, int width,
                                   double* column_dots) const {
  if (column_dots != nullptr) std::fill(column_dots, column_dots + width, 0.0);
  multiply_kernel(block_dim_, row_start_.data(), col_.data(), data_.data(), num_blocks(), X, Y,
                  width, column_dots);
}

void PackedBlockJacobi::reset() {
  num_blocks_ = 0;
  diagonal_.clear();
  inverse_.clear();
}

Status PackedBlockJacobi::update(const InformationMatrix& lambda) {
  const int d = lambda.block_dim();
  if (d != block_dim_) {
    reset();
    block_dim_ = d;
  }
  const size_t dd = static_cast<size_t>(d) * static_cast<size_t>(d);
  const int blocks = lambda.num_blocks();
  const int cached = std::min(num_blocks_, blocks);
  diagonal_.resize(static_cast<size_t>(blocks) * dd);
  inverse_.resize(static_cast<size_t>(blocks) * dd);
  last_refactored_ = 0;
  for (int b = 0; b < blocks; ++b) {
    const double* values = lambda.diagonal_block(b).data();
    double* cache = diagonal_.data() + static_cast<size_t>(b) * dd;
    if (b < cached && std::memcmp(values, cache, dd * sizeof(double)) == 0) continue;
    std::memcpy(cache, values, dd * sizeof(double));
    const Eigen::Map<const Eigen::MatrixXd> block(values, d, d);
    const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (block + block.transpose()));
    if (llt.info() != Eigen::Success) {
      reset();
      return Status::Error(StatusCode::kNotPositiveDefinite,
                           "block-Jacobi preconditioner: diagonal block " + std::to_string(b) +
                               " of the information matrix is not positive definite");
    }
    Eigen::Map<Eigen::MatrixXd>(inverse_.data() + static_cast<size_t>(b) * dd, d, d) =
        llt.solve(Eigen::MatrixXd::Identity(d, d));
    ++last_refactored_;
  }
  num_blocks_ = blocks;
  return Status::Ok();
}

void PackedBlockJacobi::apply(const double* R, double* Z, int width, double* column_dots) const {
  if (column_dots != nullptr) std::fill(column_dots, column_dots + width, 0.0);
  block_diagonal_kernel(block_dim_, inverse_.data(), num_blocks_, R, Z, width, column_dots);
}

PcgSummary solve_pcg_packed(const PackedBlockOperator& A, const PackedBlockJacobi& M,
                            const double* B, double* X, int columns, int width,
                            const PcgOptions& options, PackedPcgWorkspace& workspace) {
  PcgSummary summary;
  summary.status = options.validate();
  if (!summary.status.ok()) return summary;
  const Eigen::Index n = A.dim();
  if (M.num_blocks() != A.num_blocks() || M.block_dim() != A.block_dim() || columns < 1 ||
      width != packed_width(columns)) {
    summary.status = Status::Error(
        StatusCode::kInvalidArgument,
        "solve_pcg_packed: operator " + std::to_string(n) + " (" + std::to_string(A.num_blocks()) +
            " blocks), preconditioner " + std::to_string(M.num_blocks()) + " blocks, " +
            std::to_string(columns) + " columns packed in " + std::to_string(width));
    return summary;
  }
  const std::ptrdiff_t size = n * width;
  double* R = scratch(workspace.R, size);
  double* Z = scratch(workspace.Z, size);
  double* P = scratch(workspace.P, size);
  double* Q = scratch(workspace.Q, size);
  const auto w = static_cast<size_t>(width);
  // Per-column scalars (width each) in the workspace: no allocation once it has grown.
  workspace.scalars.assign(9 * w, 0.0);
  workspace.active.assign(w, 0);
  double* xq = workspace.scalars.data();
  double* bx = xq + w;
  double* bb = bx + w;
  double* rz = bb + w;
  double* rz_new = rz + w;
  double* rr = rz_new + w;
  double* pq = rr + w;
  double* alpha = pq + w;
  double* beta = alpha + w;
  std::vector<char>& active = workspace.active;

  // R = B - A X (warm start); restart columns whose warm start is worse than zero (pcg.h).
  A.multiply(X, Q, width, xq);
  column_dots(B, X, n, width, bx);
  column_dots(B, B, n, width, bb);
  subtract(B, Q, R, size);
  for (int c = 0; c < columns; ++c) {
    if (options.restart_worse_than_zero && xq[c] - 2.0 * bx[c] > 0.0) {
      for (Eigen::Index i = 0; i < n; ++i) {
        X[i * width + c] = 0.0;
        R[i * width + c] = B[i * width + c];
      }
      ++summary.restarted_columns;
    }
  }
  M.apply(R, Z, width, rz);
  std::copy(Z, Z + size, P);
  column_dots(R, R, n, width, rr);
  auto column_done = [&](int c) {
    return options.relative_tolerance > 0.0 &&
           std::sqrt(rr[c]) <= options.relative_tolerance * std::sqrt(bb[c]);
  };
  int active_count = 0;
  for (int c = 0; c < columns; ++c) {
    active[c] = !column_done(c);
    active_count += active[c] ? 1 : 0;
  }

  int iteration = 0;
  for (; iteration < options.max_iterations && active_count > 0; ++iteration) {
    A.multiply(P, Q, width, pq);
    for (int c = 0; c < width; ++c) {
      alpha[c] = 0.0;
      if (!active[c]) continue;
      if (!(pq[c] > 0.0)) {
        // Breakdown: either the column is already exact (p = 0) or A is not SPD.
        double pp = 0.0;
        for (Eigen::Index i = 0; i < n; ++i) pp += P[i * width + c] * P[i * width + c];
        if (pp > 0.0 && summary.status.ok()) {
          summary.status =
              Status::Error(StatusCode::kNumericalFailure,
                            "solve_pcg_packed: p^T A p = " + std::to_string(pq[c]) +
                                " <= 0 in column " + std::to_string(c) + " at iteration " +
                                std::to_string(iteration) + " (operator not positive definite?)");
        }
        active[c] = false;
        --active_count;
        continue;
      }
      alpha[c] = rz[c] / pq[c];
    }
    step_x_r(X, R, P, Q, alpha, n, width, rr);
    for (int c = 0; c < columns; ++c) {
      if (active[c] && column_done(c)) {
        active[c] = false;
        --active_count;
      }
    }
    // After the last iteration the next direction is never used: skip its preconditioner.
    if (iteration + 1 >= options.max_iterations || active_count == 0) continue;
    M.apply(R, Z, width, rz_new);
    for (int c = 0; c < width; ++c) {
      beta[c] = 0.0;
      if (!active[c]) continue;
      beta[c] = rz[c] > 0.0 ? rz_new[c] / rz[c] : 0.0;
      rz[c] = rz_new[c];
    }
    update_direction(P, Z, beta, n, width);
  }
  summary.iterations = iteration;

  // After 0 iterations R already is the true residual B - A X of the (possibly restarted) warm
  // start: a residual-only evaluation (NavFilter's certificate) costs one product, not two.
  if (options.recompute_true_residual && iteration > 0) {
    A.multiply(X, Q, width);
    subtract(B, Q, R, size);
    column_dots(R, R, n, width, rr);
  }
  summary.residual_norm.resize(columns);
  summary.relative_residual.resize(columns);
  for (int c = 0; c < columns; ++c) {
    summary.residual_norm[c] = std::sqrt(rr[c]);
    summary.relative_residual[c] = relative(summary.residual_norm[c], std::sqrt(bb[c]));
  }
  summary.max_relative_residual = summary.relative_residual.maxCoeff();
  summary.converged = options.relative_tolerance > 0.0 &&
                      summary.max_relative_residual <= options.relative_tolerance;
  return summary;
}

}  // namespace nav::core

// Exact marginals by CHOLMOD supernodal Cholesky + supernodal Takahashi selected inversion
// (recovery/exact_marginals.h; Takahashi, Fagan & Chen 1973; Lin et al., SelInv, TOMS 2011).
//
// Storage: the selected inverse Sigma uses exactly the layout of CHOLMOD's supernodal L:
// supernode s owns columns super[s]..super[s+1]-1, a sorted row list s_rows (its own columns
// first) and a column-major nrows x ncols value block at offset px[s]. The diagonal block of
// each supernode is stored in full (both triangles) so gathers never need to transpose.
// Indices are in the permuted order of the factor: Sigma_A(perm[i], perm[j]) = Sigma_P(i, j).
//
// Per supernode, with U = L_JJ^-1 (explicit, recursive triangular inverse: n^3/3 flops):
//   Y = Sigma_RR L_RJ U,  Sigma_RJ = -Y,  Sigma_JJ = U^T U + Y^T (L_RJ U).
// This is the header's recurrence rearranged so the diagonal block costs ~2/3 nc^3 + 3 nr nc^2
// instead of two full triangular solves (2 nc^3); it matters for the dense root separator
// (600 columns on sphere2500). The gather of Sigma_RR is here; the dense part of each
// supernode (Eigen) is selinv_kernel.inc, compiled twice (baseline and AVX2+FMA) and chosen at
// load time (selinv_kernel.h). The factorisation uses CHOLMOD's BLAS.

#include "nav/core/recovery/exact_marginals.h"

#include "cholmod_view.h"
#include "exact_marginals_impl.h"
#include "selinv_kernel.h"

#include <cholmod.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

namespace nav::core {

namespace {

using MatMap = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
using ConstMatMap = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

namespace {

/// Lower triangle of Lambda as a CHOLMOD matrix (stype -1). Caller frees.
cholmod_sparse* lower_to_cholmod(const Eigen::SparseMatrix<double>& Lambda, cholmod_common* c) {
  const int n = static_cast<int>(Lambda.rows());
  size_t nnz = 0;
  for (int j = 0; j < n; ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(Lambda, j); it; ++it) {
      if (it.row() >= j) ++nnz;
    }
  }
  cholmod_sparse* A = cholmod_allocate_sparse(n, n, nnz, /*sorted=*/1, /*packed=*/1,
                                              /*stype=*/-1, CHOLMOD_REAL, c);
  if (A == nullptr) throw ExactMarginalsError("ExactMarginals: CHOLMOD allocation failed");
  auto* Ap = static_cast<int*>(A->p);
  auto* Ai = static_cast<int*>(A->i);
  auto* Ax = static_cast<double*>(A->x);
  int k = 0;
  for (int j = 0; j < n; ++j) {
    Ap[j] = k;
    for (Eigen::SparseMatrix<double>::InnerIterator it(Lambda, j); it; ++it) {
      if (it.row() >= j) {
        Ai[k] = static_cast<int>(it.row());
        Ax[k] = it.value();
        ++k;
      }
    }
  }
  Ap[n] = k;
  return A;
}

/// Elimination tree of the block graph eliminated in `order` (order[k] = the block eliminated
/// k-th; `lower[j]` lists the blocks i > j with Λ_ij != 0, original numbering): parent[k] of
/// the k-th eliminated block, in elimination positions, -1 at a root. Liu's algorithm with
/// path compression (Liu, SIAM J. Matrix Anal. Appl. 1990; CSparse's cs_etree).
std::vector<int> elimination_tree(const std::vector<int>& order,
                                  const std::vector<std::vector<int>>& lower) {
  const auto nb = order.size();
  std::vector<int> position(nb);
  for (size_t k = 0; k < nb; ++k) position[static_cast<size_t>(order[k])] = static_cast<int>(k);
  std::vector<std::vector<int>> earlier(nb);  // earlier[k]: neighbours eliminated before k
  for (size_t j = 0; j < nb; ++j) {
    for (const int i : lower[j]) {
      const int a = position[j], b = position[static_cast<size_t>(i)];
      earlier[static_cast<size_t>(std::max(a, b))].push_back(std::min(a, b));
    }
  }
  std::vector<int> parent(nb, -1), ancestor(nb, -1);
  for (int k = 0; k < static_cast<int>(nb); ++k) {
    for (int i : earlier[static_cast<size_t>(k)]) {
      while (i != -1 && i < k) {
        const int next = ancestor[static_cast<size_t>(i)];
        ancestor[static_cast<size_t>(i)] = k;
        if (next == -1) parent[static_cast<size_t>(i)] = k;
        i = next;
      }
    }
  }
  return parent;
}

/// A postorder of the forest `parent` (children before their parent, every subtree a
/// contiguous range), by a depth-first walk from the roots.
std::vector<int> postorder(const std::vector<int>& parent) {
  const auto nb = parent.size();
  std::vector<std::vector<int>> children(nb);
  std::vector<int> roots;
  for (size_t k = 0; k < nb; ++k) {
    auto& siblings = parent[k] < 0 ? roots : children[static_cast<size_t>(parent[k])];
    siblings.push_back(static_cast<int>(k));
  }
  std::vector<int> result, stack;
  result.reserve(nb);
  std::vector<size_t> next_child(nb, 0);
  for (const int root : roots) {
    stack.push_back(root);
    while (!stack.empty()) {
      const auto top = static_cast<size_t>(stack.back());
      if (next_child[top] < children[top].size()) {
        stack.push_back(children[top][next_child[top]++]);
      } else {
        result.push_back(static_cast<int>(top));
        stack.pop_back();
      }
    }
  }
  return result;
}

/// `order` followed by a postorder of its elimination tree, so that every subtree, and hence
/// every supernode, is a contiguous range of columns: the form CHOLMOD's supernodal analysis
/// needs when it is given the natural ordering.
std::vector<int> postordered(const std::vector<int>& order,
                             const std::vector<std::vector<int>>& lower) {
  std::vector<int> result;
  result.reserve(order.size());
  for (const int k : postorder(elimination_tree(order, lower))) {
    result.push_back(order[static_cast<size_t>(k)]);
  }
  return result;
}

/// Fill-reducing ordering of the block graph (AMD or METIS), expanded to scalars: block order
/// first, the block_dim scalars of a block kept together and in order.
std::vector<int> block_ordering(const Eigen::SparseMatrix<double>& Lambda, int block_dim,
                                MarginalsOrdering ordering, cholmod_common* c) {
  const int n = static_cast<int>(Lambda.rows());
  const int nb = n / block_dim;
  std::vector<std::vector<int>> lower(static_cast<size_t>(nb));
  for (int j = 0; j < n; ++j) {
    const int bj = j / block_dim;
    for (Eigen::SparseMatrix<double>::InnerIterator it(Lambda, j); it; ++it) {
      const int bi = static_cast<int>(it.row()) / block_dim;
      if (bi > bj) lower[static_cast<size_t>(bj)].push_back(bi);
    }
  }
  size_t nnz = 0;
  for (auto& col : lower) {
    std::sort(col.begin(), col.end());
    col.erase(std::unique(col.begin(), col.end()), col.end());
    nnz += col.size() + 1;
  }
  cholmod_sparse* B = cholmod_allocate_sparse(nb, nb, nnz, 1, 1, -1, CHOLMOD_PATTERN, c);
  if (B == nullptr) throw ExactMarginalsError("ExactMarginals: CHOLMOD allocation failed");
  auto* Bp = static_cast<int*>(B->p);
  auto* Bi = static_cast<int*>(B->i);
  int k = 0;
  for (int j = 0; j < nb; ++j) {
    Bp[j] = k;
    Bi[k++] = j;
    for (int i : lower[static_cast<size_t>(j)]) Bi[k++] = i;
  }
  Bp[nb] = k;
  std::vector<int> block_perm(static_cast<size_t>(nb));
  const int ok = ordering == MarginalsOrdering::kBlockMetis
                     ? cholmod_metis(B, nullptr, 0, /*postorder=*/1, block_perm.data(), c)
                     : cholmod_amd(B, nullptr, 0, block_perm.data(), c);
  cholmod_free_sparse(&B, c);
  if (!ok) throw ExactMarginalsError("ExactMarginals: block ordering failed");
  block_perm = postordered(block_perm, lower);
  std::vector<int> perm(static_cast<size_t>(n));
  for (int b = 0; b < nb; ++b) {
    for (int k2 = 0; k2 < block_dim; ++k2) {
      perm[static_cast<size_t>(b * block_dim + k2)] =
          block_perm[static_cast<size_t>(b)] * block_dim + k2;
    }
  }
  return perm;
}

}  // namespace

void ExactMarginals::Impl::factor_in_cholmod_ordering(const Eigen::SparseMatrix<double>& Lambda) {
  cholmod_sparse* A = lower_to_cholmod(Lambda, &common);
  L = cholmod_analyze(A, &common);
  if (L != nullptr) cholmod_factorize(A, L, &common);
  cholmod_free_sparse(&A, &common);
  if (L != nullptr) {
    const int* cholmod_perm = static_cast<const int*>(L->Perm);
    perm.assign(cholmod_perm, cholmod_perm + n);
  }
}

void ExactMarginals::Impl::factor_permuted(const Eigen::SparseMatrix<double>& Lambda,
                                           MarginalsOrdering ordering) {
  // CHOLMOD is handed C = P Λ Pᵀ (lower triangle) in the natural ordering: it then factors C as
  // it is, where with a given ordering it would transpose Λ twice per factorisation
  // (cholmod_factorize for stype < 0) and once more in the analysis.
  perm = block_ordering(Lambda, block_dim, ordering, &common);
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P(n);
  for (int k = 0; k < n; ++k) P.indices()[perm[static_cast<size_t>(k)]] = k;
  Eigen::SparseMatrix<double> C(n, n);
  C.selfadjointView<Eigen::Lower>() = Lambda.selfadjointView<Eigen::Lower>().twistedBy(P);
  C.makeCompressed();
  cholmod_sparse view = detail::lower_view(C, /*sorted=*/false);
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_NATURAL;
  common.postorder = 0;
  L = cholmod_analyze(&view, &common);
  if (L != nullptr && L->ordering != CHOLMOD_NATURAL) {
    throw ExactMarginalsError("ExactMarginals: CHOLMOD reordered a pre-permuted matrix");
  }
  if (L != nullptr) cholmod_factorize(&view, L, &common);
}

void ExactMarginals::Impl::factor(const Eigen::SparseMatrix<double>& Lambda,
                                  MarginalsOrdering ordering) {
  const auto t0 = std::chrono::steady_clock::now();
  common.print = 0;  // errors are reported by exception, not printed
  common.supernodal = CHOLMOD_SUPERNODAL;
  common.final_asis = 1;
  if (ordering == MarginalsOrdering::kCholmodAuto) {
    factor_in_cholmod_ordering(Lambda);
  } else {
    factor_permuted(Lambda, ordering);
  }
  if (L == nullptr) {
    throw ExactMarginalsError("ExactMarginals: CHOLMOD analyse failed (status " +
                              std::to_string(common.status) + ")");
  }
  if (common.status == CHOLMOD_NOT_POSDEF || L->minor < L->n) {
    throw ExactMarginalsError(
        "ExactMarginals: information matrix is not positive definite "
        "(non-positive pivot at permuted column " +
        std::to_string(L->minor) + " of " + std::to_string(n) + ")");
  }
  if (common.status < CHOLMOD_OK || !L->is_super || !L->is_ll) {
    throw ExactMarginalsError("ExactMarginals: CHOLMOD factorisation failed (status " +
                              std::to_string(common.status) + ")");
  }
  factor_ms = ms_since(t0);
}

void ExactMarginals::Impl::invert() {
  const auto t0 = std::chrono::steady_clock::now();
  const int nsuper = static_cast<int>(L->nsuper);
  const int* Ls = rows();
  const double* Lx = static_cast<const double*>(L->x);

  col_super.assign(static_cast<size_t>(n), 0);
  for (int s = 0; s < nsuper; ++s) {
    for (int j = super()[s]; j < super()[s + 1]; ++j) col_super[static_cast<size_t>(j)] = s;
    if (!std::is_sorted(Ls + pi()[s], Ls + pi()[s + 1])) {
      throw ExactMarginalsError("ExactMarginals: CHOLMOD supernode row indices are not sorted");
    }
  }
  inv_perm.assign(static_cast<size_t>(n), 0);
  for (int k = 0; k < n; ++k) inv_perm[static_cast<size_t>(perm[static_cast<size_t>(k)])] = k;

  // No zero fill: the recurrence writes every entry of every supernode (15 MB on sphere2500).
  sigma = std::make_unique_for_overwrite<double[]>(L->xsize);
  const int max_below = static_cast<int>(L->maxesize);
  Eigen::MatrixXd srr_buffer(std::max(max_below, 1), std::max(max_below, 1));
  std::vector<int> map(static_cast<size_t>(std::max(max_below, 1)));
  const SelinvSupernodeKernel dense_kernel =
      selinv_supernode_kernel(kernel == MarginalsKernel::kBaseline);

  for (int s = nsuper - 1; s >= 0; --s) {
    const int k1 = super()[s];
    const int nc = super()[s + 1] - k1;
    const int nrows = pi()[s + 1] - pi()[s];
    const int nr = nrows - nc;
    const int* R = Ls + pi()[s] + nc;  // rows below the diagonal block, sorted
    // Gather Sigma_RR (lower triangle suffices) from the later supernodes. The rows of R
    // that are columns of one supernode t form a contiguous run; for that run the positions
    // of R[q0..] in t's row list are found once by a merge and reused for every column.
    auto S_RR = srr_buffer.topLeftCorner(nr, nr);
    int q0 = 0;
    while (q0 < nr) {
      const int t = col_super[static_cast<size_t>(R[q0])];
      const int t_first = super()[t];
      const int t_end = super()[t + 1];
      int q1 = q0;
      while (q1 < nr && R[q1] < t_end) ++q1;
      const int* t_rows = Ls + pi()[t];
      const int t_nrows = pi()[t + 1] - pi()[t];
      int pos = R[q0] - t_first;  // row R[q0] sits at its column offset in t's list
      for (int p = q0; p < nr; ++p) {
        // R[p] is in t's pattern (elimination-tree containment); guard against a bad factor.
        while (pos < t_nrows && t_rows[pos] != R[p]) ++pos;
        if (pos == t_nrows) {
          throw ExactMarginalsError("ExactMarginals: supernode pattern containment violated");
        }
        map[static_cast<size_t>(p)] = pos;
      }
      const double* t_sigma = sigma.get() + px()[t];
      for (int q = q0; q < q1; ++q) {
        const double* col = t_sigma + static_cast<std::ptrdiff_t>(R[q] - t_first) * t_nrows;
        for (int p = q0; p < nr; ++p) S_RR(p, q) = col[map[static_cast<size_t>(p)]];
      }
      q0 = q1;
    }
    // Dense part (selinv_kernel.inc), in the instruction set chosen at load time.
    dense_kernel(Lx + px()[s], nrows, nc, sigma.get() + px()[s], srr_buffer.data(),
           static_cast<int>(srr_buffer.rows()));
  }
  inversion_ms = ms_since(t0);
}

const char* auto_marginals_kernel_name() { return selinv_kernel_name(); }

ExactMarginals::ExactMarginals(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ExactMarginals::ExactMarginals(ExactMarginals&&) noexcept = default;
ExactMarginals& ExactMarginals::operator=(ExactMarginals&&) noexcept = default;
ExactMarginals::~ExactMarginals() = default;

ExactMarginals ExactMarginals::compute(const Eigen::SparseMatrix<double>& Lambda, int block_dim,
                                       MarginalsOrdering ordering, MarginalsKernel kernel) {
  if (block_dim < 1) {
    throw std::invalid_argument("ExactMarginals: block_dim " + std::to_string(block_dim) +
                                " must be >= 1");
  }
  if (Lambda.rows() != Lambda.cols() || Lambda.rows() % block_dim != 0 || Lambda.rows() == 0) {
    throw ExactMarginalsError("ExactMarginals: information matrix is " +
                              std::to_string(Lambda.rows()) + "x" + std::to_string(Lambda.cols()) +
                              ", expected square, non-empty, a multiple of block_dim " +
                              std::to_string(block_dim));
  }
  auto impl = std::make_unique<Impl>();
  impl->block_dim = block_dim;
  impl->n = static_cast<int>(Lambda.rows());
  impl->kernel = kernel;
  if (Lambda.isCompressed()) {
    impl->factor(Lambda, ordering);
  } else {
    Eigen::SparseMatrix<double> compressed = Lambda;
    compressed.makeCompressed();
    impl->factor(compressed, ordering);
  }
  impl->invert();
  return ExactMarginals(std::move(impl));
}

int ExactMarginals::block_dim() const { return impl_->block_dim; }
int ExactMarginals::num_blocks() const { return impl_->n / impl_->block_dim; }
double ExactMarginals::factor_ms() const { return impl_->factor_ms; }
double ExactMarginals::inversion_ms() const { return impl_->inversion_ms; }
Eigen::Index ExactMarginals::factor_nnz() const {
  return static_cast<Eigen::Index>(impl_->L->xsize);
}

double ExactMarginals::entry(Eigen::Index i, Eigen::Index j) const {
  if (i < 0 || j < 0 || i >= impl_->n || j >= impl_->n) {
    throw std::out_of_range("ExactMarginals::entry: index (" + std::to_string(i) + ", " +
                            std::to_string(j) + ") outside " + std::to_string(impl_->n));
  }
  const std::ptrdiff_t off = impl_->offset(impl_->inv_perm[static_cast<size_t>(i)],
                                           impl_->inv_perm[static_cast<size_t>(j)]);
  if (off < 0) {
    throw std::out_of_range("ExactMarginals::entry: (" + std::to_string(i) + ", " +
                            std::to_string(j) + ") is not in the pattern of the factor");
  }
  return impl_->sigma[static_cast<size_t>(off)];
}

namespace {
void check_block(int b, int num_blocks, const char* where) {
  if (b < 0 || b >= num_blocks) {
    throw std::out_of_range(std::string(where) + ": block " + std::to_string(b) + " outside [0, " +
                            std::to_string(num_blocks) + ")");
  }
}
}  // namespace

bool ExactMarginals::in_pattern(int a, int b) const {
  check_block(a, num_blocks(), "ExactMarginals::in_pattern");
  check_block(b, num_blocks(), "ExactMarginals::in_pattern");
  const int d = impl_->block_dim;
  for (int r = 0; r < d; ++r) {
    for (int c = 0; c < d; ++c) {
      if (impl_->offset(impl_->inv_perm[static_cast<size_t>(a * d + r)],
                        impl_->inv_perm[static_cast<size_t>(b * d + c)]) < 0) {
        return false;
      }
    }
  }
  return true;
}

Eigen::MatrixXd ExactMarginals::marginals() const {
  const Eigen::Index d = block_dim();
  Eigen::MatrixXd stacked(num_blocks() * d, d);
  for (int b = 0; b < num_blocks(); ++b) stacked.middleRows(b * d, d) = marginal(b);
  return stacked;
}

Eigen::MatrixXd ExactMarginals::marginal(int block) const {
  check_block(block, num_blocks(), "ExactMarginals::marginal");
  const int d = impl_->block_dim;
  Eigen::MatrixXd S(d, d);
  for (int c = 0; c < d; ++c) {
    for (int r = c; r < d; ++r) {
      const std::ptrdiff_t off = impl_->offset(impl_->inv_perm[static_cast<size_t>(block * d + r)],
                                               impl_->inv_perm[static_cast<size_t>(block * d + c)]);
      // A diagonal block of Lambda is in the pattern of L unless Lambda stores explicit
      // structural zeros there; then the entry is not kept and is solved for below.
      if (off < 0) return joint(block, block).topLeftCorner(d, d);
      S(r, c) = S(c, r) = impl_->sigma[static_cast<size_t>(off)];
    }
  }
  return S;
}

Eigen::MatrixXd ExactMarginals::block_column(int block) const {
  check_block(block, num_blocks(), "ExactMarginals::block_column");
  const int d = impl_->block_dim;
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(impl_->n, d);
  E.middleRows(Eigen::Index{block} * d, d).setIdentity();
  Eigen::MatrixXd X(impl_->n, d);
  impl_->solve(E, X);
  return X;
}

Eigen::MatrixXd ExactMarginals::joint(int a, int b) const {
  check_block(a, num_blocks(), "ExactMarginals::joint");
  check_block(b, num_blocks(), "ExactMarginals::joint");
  const int d = impl_->block_dim;
  Eigen::MatrixXd J(2 * d, 2 * d);
  const bool direct = in_pattern(a, b) && in_pattern(a, a) && in_pattern(b, b);
  if (direct) {
    for (int c = 0; c < 2 * d; ++c) {
      const int gc = (c < d ? a * d + c : b * d + c - d);
      for (int r = 0; r < 2 * d; ++r) {
        const int gr = (r < d ? a * d + r : b * d + r - d);
        J(r, c) = impl_->sigma[static_cast<size_t>(impl_->offset(
            impl_->inv_perm[static_cast<size_t>(gr)], impl_->inv_perm[static_cast<size_t>(gc)]))];
      }
    }
    return J;
  }
  // Outside the pattern: solve the columns of blocks a and b exactly with the factor.
  const int n = impl_->n;
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, 2 * d);
  for (int k = 0; k < 2 * d; ++k) E(k < d ? a * d + k : b * d + k - d, k) += 1.0;
  Eigen::MatrixXd X(n, 2 * d);
  impl_->solve(E, X);
  for (int k = 0; k < 2 * d; ++k) {
    for (int r = 0; r < 2 * d; ++r) J(r, k) = X(r < d ? a * d + r : b * d + r - d, k);
  }
  J = 0.5 * (J + J.transpose()).eval();
  return J;
}

}  // namespace nav::core

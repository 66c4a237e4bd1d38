// A sparse LDLᵀ factor kept equal to Λ by CHOLMOD's row modifications and rank updates
// (recovery/kept_equal_factor.h).
#include "nav/core/recovery/kept_equal_factor.h"

#include <cholmod.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <algorithm>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "cholmod_view.h"
#include "ldl_append.h"
#include "ldl_pivot.h"
#include "ldl_solve.h"

namespace nav::core {

struct KeptEqualFactor::Cholmod {
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  Cholmod() {
    cholmod_start(&c);
    c.print = 0;  // failures are reported through Status
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_NATURAL;  // slot space is already ordered
    c.postorder = 0;
    // Refactorisations run supernodal (dense BLAS kernels on the fill) and are converted to the
    // simplicial LDLᵀ the Modify module works on. No relaxed amalgamation: its explicit zeros
    // would stay in the simplicial factor and cost every later solve and modification.
    c.supernodal = CHOLMOD_SUPERNODAL;
    for (size_t& n : c.nrelax) n = 0;
    for (double& z : c.zrelax) z = 0.0;
  }
  ~Cholmod() {
    if (L != nullptr) cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }
  Cholmod(const Cholmod&) = delete;
  Cholmod& operator=(const Cholmod&) = delete;
};

namespace {

using Entry = std::pair<int, double>;  // (row, value) of one column

/// An n x columns.size() packed CHOLMOD matrix, rows sorted and duplicates summed per column
/// (cholmod_rowadd assigns a repeated row instead of summing it).
cholmod_sparse* to_cholmod(std::vector<std::vector<Entry>>& columns, size_t n, cholmod_common* c) {
  size_t nnz = 0;
  for (auto& col : columns) {
    std::sort(col.begin(), col.end(),
              [](const Entry& a, const Entry& b) { return a.first < b.first; });
    size_t out = 0;
    for (size_t k = 0; k < col.size(); ++k) {
      if (out > 0 && col[out - 1].first == col[k].first) {
        col[out - 1].second += col[k].second;
      } else {
        col[out++] = col[k];
      }
    }
    col.resize(out);
    nnz += out;
  }
  cholmod_sparse* s = cholmod_allocate_sparse(n, columns.size(), std::max<size_t>(nnz, 1), 1, 1, 0,
                                              CHOLMOD_REAL, c);
  if (s == nullptr) return nullptr;
  auto* p = static_cast<int*>(s->p);
  auto* i = static_cast<int*>(s->i);
  auto* x = static_cast<double*>(s->x);
  int k = 0;
  for (size_t j = 0; j < columns.size(); ++j) {
    p[j] = k;
    for (const Entry& e : columns[j]) {
      i[k] = e.first;
      x[k++] = e.second;
    }
  }
  p[columns.size()] = k;
  return s;
}

/// Fill-reducing order of the block graph of blocks 1 .. n-1 (the robot left out): order[k] =
/// the block at position k. AMD, or with 0 < `recent` < n-1 constrained AMD (CAMD) with the
/// newest `recent` blocks after all others (file comment).
std::vector<int> block_order(const InformationMatrix& lambda, int recent, cholmod_common* c) {
  const int nb = lambda.num_blocks() - 1;
  std::vector<std::vector<int>> lower(static_cast<size_t>(nb));
  size_t nnz = 0;
  for (int j = 0; j < nb; ++j) {
    auto& col = lower[static_cast<size_t>(j)];
    col.push_back(j);
    for (int k = 0; k < lambda.num_neighbours(j + 1); ++k) {
      const int i = lambda.neighbour(j + 1, k) - 1;
      if (i > j) col.push_back(i);
    }
    std::sort(col.begin(), col.end());
    nnz += col.size();
  }
  std::vector<int> order(static_cast<size_t>(nb));
  if (nb == 0) return order;
  cholmod_sparse* B = cholmod_allocate_sparse(nb, nb, nnz, 1, 1, -1, CHOLMOD_PATTERN, c);
  if (B == nullptr) return {};
  auto* p = static_cast<int*>(B->p);
  auto* i = static_cast<int*>(B->i);
  int k = 0;
  for (int j = 0; j < nb; ++j) {
    p[j] = k;
    for (int r : lower[static_cast<size_t>(j)]) i[k++] = r;
  }
  p[nb] = k;
  int ok = 0;
  if (recent > 0 && recent < nb) {  // else one set: plain AMD (CAMD wants sets < nb)
    std::vector<int> group(static_cast<size_t>(nb), 0);
    std::fill(group.end() - recent, group.end(), 1);  // the blocks are in time order
    ok = cholmod_camd(B, nullptr, 0, group.data(), order.data(), c);
  } else {
    ok = cholmod_amd(B, nullptr, 0, order.data(), c);
  }
  cholmod_free_sparse(&B, c);
  if (!ok) return {};
  for (int& b : order) ++b;
  return order;
}

/// The smallest pivot D_kk of a simplicial LDLᵀ factor (the first entry of each column of L):
/// CHOLMOD's LDLᵀ does not stop at a negative pivot, so positive definiteness is checked here.
double smallest_pivot(const cholmod_factor& L) {
  const auto* p = static_cast<const int*>(L.p);
  const auto* x = static_cast<const double*>(L.x);
  double smallest = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < L.n; ++k) smallest = std::min(smallest, x[p[k]]);
  return smallest;
}

Status cholmod_failure(const char* where, const cholmod_common& c) {
  return Status::Error(
      StatusCode::kNotPositiveDefinite,
      std::string("KeptEqualFactor::") + where + ": CHOLMOD status " + std::to_string(c.status) +
          (c.status == CHOLMOD_OK ? " but a pivot <= 0: Λ is not positive definite" : ""));
}

}  // namespace

KeptEqualFactor::KeptEqualFactor() : factor_(std::make_unique<Cholmod>()) {}
KeptEqualFactor::~KeptEqualFactor() = default;
KeptEqualFactor::KeptEqualFactor(const KeptEqualFactor&) : KeptEqualFactor() {}
KeptEqualFactor& KeptEqualFactor::operator=(const KeptEqualFactor& other) {
  if (this != &other) reset();
  return *this;
}

bool KeptEqualFactor::has_factor() const { return factor_->L != nullptr; }

int KeptEqualFactor::spare_blocks() const { return has_factor() ? robot_slot_ - next_slot_ : 0; }

int KeptEqualFactor::slot_row(int block, int i) const {
  return slot_[static_cast<size_t>(block)] * factored_.block_dim() + i;
}

void KeptEqualFactor::reset() {
  if (factor_->L != nullptr) cholmod_free_factor(&factor_->L, &factor_->c);
  slot_.clear();
  present_.clear();
  factored_ = InformationMatrix(1);
  last_update_ = {};  // a refactorisation modified nothing
  changed_rows_.reset();
}

double KeptEqualFactor::factor_nnz() const {
  if (!has_factor()) return 0.0;
  const auto* nz = static_cast<const int*>(factor_->L->nz);
  return std::accumulate(nz, nz + factor_->L->n, 0.0);
}

Status KeptEqualFactor::factor(const InformationMatrix& lambda, int spare_blocks,
                               int recent_blocks) {
  reset();
  if (lambda.num_blocks() == 0 || spare_blocks < 0 || recent_blocks < 0) {
    return Status::Error(
        StatusCode::kInvalidArgument,
        "KeptEqualFactor::factor: needs a non-empty Λ, spare_blocks >= 0 and recent_blocks >= 0 "
        "(got " +
            std::to_string(lambda.num_blocks()) + " blocks, " + std::to_string(spare_blocks) +
            " spare, " + std::to_string(recent_blocks) + " recent)");
  }
  cholmod_common* c = &factor_->c;
  const std::vector<int> order = block_order(lambda, recent_blocks, c);
  const int n = lambda.num_blocks(), d = lambda.block_dim();
  if (static_cast<int>(order.size()) != n - 1) return cholmod_failure("factor (ordering)", *c);
  slot_.assign(static_cast<size_t>(n), 0);
  for (int k = 0; k < n - 1; ++k) slot_[static_cast<size_t>(order[static_cast<size_t>(k)])] = k;
  next_slot_ = n - 1;
  robot_slot_ = n - 1 + spare_blocks;
  slot_[0] = robot_slot_;
  present_.assign(static_cast<size_t>(n), 1);
  factored_ = lambda;
  // Λ in slot space (lower triangle), the reserved slots the identity.
  const int dim = (robot_slot_ + 1) * d;
  std::vector<Eigen::Triplet<double>> lower;
  for (int b = 0; b < n; ++b) {
    const auto& diagonal = lambda.diagonal_block(b);
    for (int j = 0; j < d; ++j) {
      for (int i = j; i < d; ++i)
        lower.emplace_back(slot_row(b, i), slot_row(b, j), diagonal(i, j));
    }
    for (int k = 0; k < lambda.num_neighbours(b); ++k) {
      const int nb = lambda.neighbour(b, k);
      if (slot_[static_cast<size_t>(nb)] < slot_[static_cast<size_t>(b)]) continue;
      const auto& block = lambda.neighbour_block(b, k);  // Λ_{b,nb}: rows b, columns nb
      for (int j = 0; j < d; ++j) {
        for (int i = 0; i < d; ++i)
          lower.emplace_back(slot_row(nb, i), slot_row(b, j), block(j, i));
      }
    }
  }
  for (int r = next_slot_ * d; r < robot_slot_ * d; ++r) lower.emplace_back(r, r, 1.0);
  Eigen::SparseMatrix<double> a(dim, dim);
  a.setFromTriplets(lower.begin(), lower.end());
  a.makeCompressed();
  cholmod_sparse view = detail::lower_view(a, /*sorted=*/true);
  factor_->L = cholmod_analyze(&view, c);
  if (factor_->L == nullptr) return cholmod_failure("factor (analysis)", *c);
  if (!cholmod_factorize(&view, factor_->L, c) || c->status != CHOLMOD_OK ||
      factor_->L->minor < factor_->L->n ||
      !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/0,
                             /*to_monotonic=*/1, factor_->L, c) ||
      !(smallest_pivot(*factor_->L) > 0.0)) {
    const Status s = cholmod_failure("factor", *c);
    reset();
    return s;
  }
  return Status::Ok();
}

void KeptEqualFactor::delete_block(int block) {
  for (int j = 0; j < factored_.block_dim(); ++j) {
    cholmod_rowdel(static_cast<size_t>(slot_row(block, j)), nullptr, factor_->L, &factor_->c);
  }
  present_[static_cast<size_t>(block)] = 0;
}

void KeptEqualFactor::add_block(const InformationMatrix& lambda, int block) {
  const int d = lambda.block_dim();
  const auto& diagonal = lambda.diagonal_block(block);
  std::vector<detail::AppendCoupling> couplings;  // Λ_{block,nb}; the others enter later
  for (int k = 0; k < lambda.num_neighbours(block); ++k) {
    const int nb = lambda.neighbour(block, k);
    if (present_[static_cast<size_t>(nb)]) {
      couplings.push_back({slot_row(nb, 0), lambda.neighbour_block(block, k)});
    }
  }
  const detail::AppendResult appended =
      detail::append_block(factor_->L, &factor_->c, slot_row(block, 0), diagonal, couplings);
  if (appended == detail::AppendResult::kOutOfMemory) return;  // c.status says why
  present_[static_cast<size_t>(block)] = 1;
  if (appended == detail::AppendResult::kAppended) {
    ++last_update_.blocks_appended;
    return;
  }
  // Row by row (a neighbour later in the factor, or rows the block left behind).
  std::vector<std::vector<Entry>> column(1);
  for (int j = 0; j < d; ++j) {
    column[0].clear();
    for (const auto& c : couplings) {
      for (int i = 0; i < d; ++i) column[0].emplace_back(c.first_row + i, c.block(j, i));
    }
    for (int i = 0; i <= j; ++i) column[0].emplace_back(slot_row(block, i), diagonal(i, j));
    cholmod_sparse* r = to_cholmod(column, factor_->L->n, &factor_->c);
    if (r == nullptr) return;  // c.status says why
    cholmod_rowadd(static_cast<size_t>(slot_row(block, j)), r, factor_->L, &factor_->c);
    cholmod_free_sparse(&r, &factor_->c);
  }
}

namespace {

/// Λ_ab − F_ab for stored blocks (zero where neither stores one).
Eigen::MatrixXd increment(const InformationMatrix& lambda, const InformationMatrix& factored, int a,
                          int b) {
  const int d = lambda.block_dim();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(d, d);
  if (a == b) return lambda.diagonal_block(a) - factored.diagonal_block(a);
  if (const auto* l = lambda.find_block(a, b)) out += *l;
  if (const auto* f = factored.find_block(a, b)) out -= *f;
  return out;
}

/// Groups of `changed` joined by a changed off-diagonal block (union-find), each sorted.
std::vector<std::vector<int>> connected_groups(const InformationMatrix& lambda,
                                               const InformationMatrix& factored,
                                               const std::vector<int>& changed) {
  std::vector<int> index(static_cast<size_t>(factored.num_blocks()), -1);
  for (size_t k = 0; k < changed.size(); ++k)
    index[static_cast<size_t>(changed[k])] = static_cast<int>(k);
  std::vector<int> parent(changed.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)];
    return x;
  };
  auto join_neighbours = [&](const InformationMatrix& m, int a) {
    for (int k = 0; k < m.num_neighbours(a); ++k) {
      const int nb = m.neighbour(a, k);
      if (nb >= factored.num_blocks() || index[static_cast<size_t>(nb)] < 0) continue;
      if (increment(lambda, factored, a, nb).isZero(0.0)) continue;
      parent[static_cast<size_t>(root(index[static_cast<size_t>(a)]))] =
          root(index[static_cast<size_t>(nb)]);
    }
  };
  for (int a : changed) {
    join_neighbours(lambda, a);
    join_neighbours(factored, a);
  }
  std::vector<std::vector<int>> groups(changed.size());
  for (size_t k = 0; k < changed.size(); ++k) {
    groups[static_cast<size_t>(root(static_cast<int>(k)))].push_back(changed[k]);
  }
  groups.erase(
      std::remove_if(groups.begin(), groups.end(), [](const auto& g) { return g.empty(); }),
      groups.end());
  return groups;
}

}  // namespace

bool KeptEqualFactor::rank_update(const InformationMatrix& lambda,
                                  const std::vector<int>& changed) {
  const int d = lambda.block_dim();
  std::vector<std::vector<Entry>> plus, minus;
  for (std::vector<int> group : connected_groups(lambda, factored_, changed)) {
    std::sort(group.begin(), group.end(), [&](int a, int b) {
      return slot_[static_cast<size_t>(a)] < slot_[static_cast<size_t>(b)];
    });
    const auto m = static_cast<Eigen::Index>(group.size()) * d;
    Eigen::MatrixXd delta(m, m);
    for (size_t a = 0; a < group.size(); ++a) {
      for (size_t b = 0; b < group.size(); ++b) {
        delta.block(static_cast<Eigen::Index>(a) * d, static_cast<Eigen::Index>(b) * d, d, d) =
            increment(lambda, factored_, group[a], group[b]);
      }
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (delta + delta.transpose()));
    const double floor = 1e-12 * eig.eigenvalues().cwiseAbs().maxCoeff();
    for (Eigen::Index e = 0; e < m; ++e) {
      const double value = eig.eigenvalues()[e];
      if (std::abs(value) <= floor) continue;
      auto& target = value > 0 ? plus : minus;
      target.emplace_back();
      const Eigen::VectorXd column = std::sqrt(std::abs(value)) * eig.eigenvectors().col(e);
      for (Eigen::Index r = 0; r < m; ++r) {
        target.back().emplace_back(
            slot_row(group[static_cast<size_t>(r / d)], static_cast<int>(r % d)), column[r]);
      }
    }
  }
  last_update_.update_rank = static_cast<int>(plus.size());
  last_update_.downdate_rank = static_cast<int>(minus.size());
  for (int update = 1; update >= 0; --update) {  // the update first: the downdate must stay PD
    auto& columns = update ? plus : minus;
    if (columns.empty()) continue;
    cholmod_sparse* cc = to_cholmod(columns, factor_->L->n, &factor_->c);
    if (cc == nullptr || !cholmod_updown(update, cc, factor_->L, &factor_->c)) {
      if (cc != nullptr) cholmod_free_sparse(&cc, &factor_->c);
      return false;
    }
    cholmod_free_sparse(&cc, &factor_->c);
  }
  return true;
}

void KeptEqualFactor::copy_rows(const InformationMatrix& lambda, const std::vector<int>& rows) {
  std::vector<char> in(static_cast<size_t>(lambda.num_blocks()), 0);
  for (int b : rows) in[static_cast<size_t>(b)] = 1;
  for (int b : rows) {
    if (b < factored_.num_blocks()) factored_.clear_row(b);
  }
  while (factored_.num_blocks() < lambda.num_blocks()) factored_.add_block();
  for (int b : rows) {
    factored_.add_to_block(b, b, lambda.diagonal_block(b));
    for (int k = 0; k < lambda.num_neighbours(b); ++k) {
      const int nb = lambda.neighbour(b, k);
      if (!in[static_cast<size_t>(nb)] || nb > b) {
        factored_.add_to_block(b, nb, lambda.neighbour_block(b, k));
      }
    }
  }
}

Status KeptEqualFactor::update(const InformationMatrix& lambda) {
  last_update_ = {};
  changed_rows_.reset();
  const int n_old = factored_.num_blocks(), n_new = lambda.num_blocks();
  if (!has_factor() || lambda.block_dim() != factored_.block_dim() || n_new < n_old) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "KeptEqualFactor::update: a factor of " + std::to_string(n_old) +
                             " blocks of " + std::to_string(factored_.block_dim()) +
                             " cannot follow Λ of " + std::to_string(n_new) + " blocks of " +
                             std::to_string(lambda.block_dim()));
  }
  if (n_new - n_old > spare_blocks()) {
    return Status::Error(StatusCode::kOutOfRange,
                         "KeptEqualFactor::update: " + std::to_string(n_new - n_old) +
                             " appended states, " + std::to_string(spare_blocks()) +
                             " reserved slots left");
  }
  std::vector<int> replaced = factored_.neighbours(0);
  replaced.push_back(0);
  std::sort(replaced.begin(), replaced.end());
  std::vector<char> is_replaced(static_cast<size_t>(n_old), 0);
  for (int b : replaced) is_replaced[static_cast<size_t>(b)] = 1;
  std::vector<int> changed;
  for (int b = 1; b < n_old; ++b) {
    if (!is_replaced[static_cast<size_t>(b)] &&
        lambda.diagonal_block(b) != factored_.diagonal_block(b)) {
      changed.push_back(b);
    }
  }
  // The robot's one neighbour keeps its rows when only its diagonal block changed (ldl_pivot.h);
  // kept = -1 when the robot has more neighbours (never the robot itself).
  const int kept = replaced.size() == 2 ? replaced[1] : -1;
  for (int b : replaced) {
    if (b != kept) delete_block(b);
  }
  const bool in_place = kept > 0 && modify_pivot(lambda, kept);
  if (kept > 0 && !in_place) delete_block(kept);
  if (!changed.empty() && !rank_update(lambda, changed)) {
    const Status s = cholmod_failure("update (rank update)", factor_->c);
    reset();
    return s;
  }
  for (int b = n_old; b < n_new; ++b) {
    slot_.push_back(next_slot_++);
    present_.push_back(0);
  }
  std::vector<int> added;  // the robot last
  for (int b : replaced) {
    if (b != 0 && !(in_place && b == kept)) added.push_back(b);
  }
  for (int b = n_old; b < n_new; ++b) added.push_back(b);
  added.push_back(0);
  for (int b : added) add_block(lambda, b);
  if (factor_->c.status != CHOLMOD_OK || !(smallest_pivot(*factor_->L) > 0.0)) {
    const Status s = cholmod_failure("update (row modifications)", factor_->c);
    reset();
    return s;
  }
  last_update_.rows_replaced = static_cast<int>(replaced.size()) - (in_place ? 1 : 0);
  last_update_.pivots_modified = in_place ? 1 : 0;
  last_update_.rows_added = n_new - n_old;
  last_update_.blocks_updated = static_cast<int>(changed.size());
  added.insert(added.end(), changed.begin(), changed.end());
  if (in_place) added.push_back(kept);
  copy_rows(lambda, added);
  changed_rows_ = std::move(added);
  return Status::Ok();
}

bool KeptEqualFactor::modify_pivot(const InformationMatrix& lambda, int block) {
  // Its couplings to the blocks in the factor now (all but the deleted robot and the states
  // appended since) must be unchanged: then its rows of L are (ldl_pivot.h).
  for (const InformationMatrix* m : {&lambda, static_cast<const InformationMatrix*>(&factored_)}) {
    for (int k = 0; k < m->num_neighbours(block); ++k) {
      const int nb = m->neighbour(block, k);
      if (nb == 0 || nb >= factored_.num_blocks()) continue;
      if (!increment(lambda, factored_, block, nb).isZero(0.0)) return false;
    }
  }
  return detail::set_pivot_block(ldl(), static_cast<double*>(factor_->L->x), slot_row(block, 0),
                                 lambda.diagonal_block(block));
}

detail::SimplicialLdl KeptEqualFactor::ldl() const {
  const cholmod_factor& L = *factor_->L;
  return {static_cast<int>(L.n), static_cast<const int*>(L.p), static_cast<const int*>(L.nz),
          static_cast<const int*>(L.i), static_cast<const double*>(L.x)};
}

}  // namespace nav::core

// A block of rows appended to a simplicial LDLᵀ factor as one block (ldl_append.h).
#include "ldl_append.h"

#include <algorithm>

#include "ldl_pivot.h"

namespace nav::core::detail {
namespace {

/// The factor's arrays (CHOLMOD's simplicial storage, int indices). `row` and `value` move when
/// a column is reallocated: re-read them after any cholmod_reallocate_column.
struct Columns {
  int* p;
  int* nz;
  int* next;
  int* row;
  double* value;
  explicit Columns(cholmod_factor* L)
      : p(static_cast<int*>(L->p)),
        nz(static_cast<int*>(L->nz)),
        next(static_cast<int*>(L->next)),
        row(static_cast<int*>(L->i)),
        value(static_cast<double*>(L->x)) {}
  int parent(int j) const { return nz[j] > 1 ? row[p[j] + 1] : -1; }
  int room(int j) const { return p[next[j]] - p[j]; }
};

/// The rows of the forward solve: the neighbours' rows and their ancestors in the elimination
/// tree before `first`, ascending (a topological order), with index[row] their position.
std::vector<int> reach(const Columns& L, int first, int d,
                       const std::vector<AppendCoupling>& couplings, std::vector<int>* index) {
  std::vector<int> rows;
  for (const AppendCoupling& c : couplings) {
    for (int i = 0; i < d; ++i) {
      for (int r = c.first_row + i; r >= 0 && r < first && (*index)[r] < 0; r = L.parent(r)) {
        (*index)[r] = 0;
        rows.push_back(r);
      }
    }
  }
  std::sort(rows.begin(), rows.end());
  for (size_t k = 0; k < rows.size(); ++k) (*index)[rows[k]] = static_cast<int>(k);
  return rows;
}

/// The forward solve L_{<b} Y = A_b over `rows` (Y row-major, d per row), each row replaced by
/// L_bj = Y_j / D_j, and `schur` reduced by Y_j Y_jᵀ / D_j. `after` collects the rows after the
/// block stored in those columns. False when a column stores a row of the block, a nonzero
/// value after it, a row outside the reach, or a pivot that is not positive.
bool forward(const Columns& L, int first, int d, const std::vector<int>& rows,
             const std::vector<int>& index, double* Y, Eigen::MatrixXd* schur,
             std::vector<int>* after) {
  Eigen::VectorXd y(d);
  for (size_t k = 0; k < rows.size(); ++k) {
    const int j = rows[k];
    const int begin = L.p[j], end = begin + L.nz[j];
    const double dj = L.value[begin];
    if (!(dj > 0.0)) return false;
    double* yk = Y + k * static_cast<size_t>(d);
    for (int c = 0; c < d; ++c) y[c] = yk[c];
    for (int q = begin + 1; q < end; ++q) {
      const int i = L.row[q];
      if (i >= first + d) {
        if (L.value[q] != 0.0) return false;  // a later row depends on the reach
        after->push_back(i);
        continue;
      }
      if (i >= first || index[i] < 0) return false;
      double* yi = Y + static_cast<size_t>(index[i]) * static_cast<size_t>(d);
      const double l = L.value[q];
      for (int c = 0; c < d; ++c) yi[c] -= l * y[c];
    }
    schur->selfadjointView<Eigen::Lower>().rankUpdate(y, -1.0 / dj);
    for (int c = 0; c < d; ++c) yk[c] = y[c] / dj;
  }
  std::sort(after->begin(), after->end());
  after->erase(std::unique(after->begin(), after->end()), after->end());
  return true;
}

/// Room for `extra` more entries in each of `rows`' columns and for `need[t]` in the block's.
/// A column reallocation that has to grow the factor also packs every column to its length
/// plus c->grow2, which would undo the room made before it; so the factor is grown first, once,
/// by the space all of this pass's reallocations take (CHOLMOD's own sizes: grow1 · need +
/// grow2 per column, grow0 times the total). Only storage moves: the values are unchanged.
AppendResult make_room(cholmod_factor* L, cholmod_common* c, const std::vector<int>& rows,
                       int extra, int first, const std::vector<int>& need) {
  const Columns cols(L);  // p, nz and next stay where they are; only their values change
  const int n = static_cast<int>(L->n);
  std::vector<std::pair<int, int>> moves;  // (column, size) to reallocate
  for (int j : rows) {
    if (cols.nz[j] + extra > cols.room(j)) moves.emplace_back(j, cols.nz[j] + extra);
  }
  for (size_t t = 0; t < need.size(); ++t) {
    const int j = first + static_cast<int>(t);
    if (need[t] > cols.room(j)) moves.emplace_back(j, need[t]);
  }
  double space = 0.0;
  for (const auto& [j, size] : moves) {
    space += std::min<double>(c->grow1 * size + static_cast<double>(c->grow2), n - j);
  }
  const double used = cols.p[n];
  if (used + space > static_cast<double>(L->nzmax) &&
      !cholmod_reallocate_factor(
          static_cast<size_t>(std::max(1.2, c->grow0) * (static_cast<double>(L->nzmax) + space)), L,
          c)) {
    return AppendResult::kOutOfMemory;
  }
  const double growths = c->nrealloc_factor;
  for (const auto& [j, size] : moves) {
    if (!cholmod_reallocate_column(static_cast<size_t>(j), static_cast<size_t>(size), L, c)) {
      return AppendResult::kOutOfMemory;
    }
  }
  // Grown again after all (CHOLMOD's rounding of the sizes): the columns moved first may have
  // lost their room; the caller adds the rows another way.
  return c->nrealloc_factor == growths ? AppendResult::kAppended : AppendResult::kNotApplicable;
}

/// Inserts rows [first, first + d) with values `l` into column j before its rows after them.
void insert_rows(Columns& L, int j, int first, int d, const double* l) {
  const int begin = L.p[j], end = begin + L.nz[j];
  int position = end;
  while (position > begin + 1 && L.row[position - 1] >= first) --position;
  for (int q = end - 1; q >= position; --q) {
    L.row[q + d] = L.row[q];
    L.value[q + d] = L.value[q];
  }
  for (int c = 0; c < d; ++c) {
    L.row[position + c] = first + c;
    L.value[position + c] = l[c];
  }
  L.nz[j] += d;
}

}  // namespace

AppendResult append_block(cholmod_factor* L, cholmod_common* c, int first,
                          const Eigen::MatrixXd& diagonal,
                          const std::vector<AppendCoupling>& couplings) {
  const int d = static_cast<int>(diagonal.rows());
  const int n = static_cast<int>(L->n);
  if (L->is_super || L->is_ll || L->xtype != CHOLMOD_REAL || first < 0 || first + d > n) {
    return AppendResult::kNotApplicable;
  }
  Columns cols(L);
  for (int t = 0; t < d; ++t) {
    if (cols.nz[first + t] != 1) return AppendResult::kNotApplicable;
  }
  for (const AppendCoupling& cp : couplings) {
    if (cp.first_row < 0 || cp.first_row + d > first) return AppendResult::kNotApplicable;
  }
  std::vector<int> index(static_cast<size_t>(n), -1);
  const std::vector<int> rows = reach(cols, first, d, couplings, &index);
  // Y = A_b by rows: A(nb + i, j) = Λ_{b,nb}(j, i).
  std::vector<double> Y(rows.size() * static_cast<size_t>(d), 0.0);
  for (const AppendCoupling& cp : couplings) {
    for (int i = 0; i < d; ++i) {
      double* yi = Y.data() + static_cast<size_t>(index[cp.first_row + i]) * d;
      for (int j = 0; j < d; ++j) yi[j] += cp.block(j, i);
    }
  }
  Eigen::MatrixXd schur = 0.5 * (diagonal + diagonal.transpose());
  std::vector<int> after;
  if (!forward(cols, first, d, rows, index, Y.data(), &schur, &after)) {
    return AppendResult::kNotApplicable;
  }
  Eigen::MatrixXd unit;
  Eigen::VectorXd pivot;
  if (!dense_ldl(schur, &unit, &pivot)) return AppendResult::kNotApplicable;
  // The block's columns: its pivot, the rows below it in the block, and as explicit zeros the
  // rows after it that the reach stores (so that each column's pattern stays within its
  // parent's, as a row addition leaves it).
  const int tail = static_cast<int>(after.size());
  std::vector<int> need(static_cast<size_t>(d));
  for (int t = 0; t < d; ++t) need[static_cast<size_t>(t)] = d - t + tail;
  const AppendResult room = make_room(L, c, rows, d, first, need);
  if (room != AppendResult::kAppended) return room;
  cols = Columns(L);
  for (size_t k = 0; k < rows.size(); ++k) {
    insert_rows(cols, rows[k], first, d, Y.data() + k * static_cast<size_t>(d));
  }
  for (int t = 0; t < d; ++t) {
    const int j = first + t;
    int q = cols.p[j];
    cols.row[q] = j;
    cols.value[q++] = pivot[t];
    for (int i = t + 1; i < d; ++i, ++q) {
      cols.row[q] = first + i;
      cols.value[q] = unit(i, t);
    }
    for (int r : after) {
      cols.row[q] = r;
      cols.value[q++] = 0.0;
    }
    cols.nz[j] = d - t + tail;
  }
  return AppendResult::kAppended;
}

}  // namespace nav::core::detail

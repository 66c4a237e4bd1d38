// A new diagonal block set in its pivot block in place (ldl_pivot.h).
#include "ldl_pivot.h"

#include <vector>

namespace nav::core::detail {
namespace {

/// Positions in `value` of the block's unit lower triangle (position(i, j), i > j) and of its
/// pivots (position(j, j)), or an empty vector when an entry is missing or a stored value
/// below the block is not zero.
std::vector<int> pivot_positions(const SimplicialLdl& L, const double* value, int first, int d) {
  std::vector<int> position(static_cast<size_t>(d * d), -1);
  for (int j = 0; j < d; ++j) {
    const int column = first + j;
    const int begin = L.p[column], end = begin + L.nz[column];
    if (L.row[begin] != column) return {};  // the pivot D_j comes first
    position[static_cast<size_t>(j * d + j)] = begin;
    for (int k = begin + 1; k < end; ++k) {
      const int i = L.row[k] - first;
      if (i >= d) {
        if (value[k] != 0.0) return {};  // a later row depends on the block
      } else if (i > j) {
        position[static_cast<size_t>(i * d + j)] = k;
      }
    }
    for (int i = j + 1; i < d; ++i) {
      if (position[static_cast<size_t>(i * d + j)] < 0) return {};
    }
  }
  return position;
}

/// T = Σ_{j < first} L_bj D_j L_bjᵀ, L_bj the entries of column j in the block's rows (the
/// rows of each column are sorted, so they sit just above the column's later rows).
Eigen::MatrixXd older_contribution(const SimplicialLdl& L, const double* value, int first, int d) {
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(d, d);
  Eigen::VectorXd row(d);
  for (int j = 0; j < first; ++j) {
    const int begin = L.p[j];
    int k = begin + L.nz[j] - 1;
    while (k > begin && L.row[k] >= first + d) --k;
    if (k == begin || L.row[k] < first) continue;  // no entry in the block's rows
    row.setZero();
    for (; k > begin && L.row[k] >= first; --k) row[L.row[k] - first] = value[k];
    T.selfadjointView<Eigen::Lower>().rankUpdate(row, value[begin]);
  }
  return T.selfadjointView<Eigen::Lower>();
}

}  // namespace

bool set_pivot_block(const SimplicialLdl& L, double* value, int first,
                     const Eigen::MatrixXd& diagonal) {
  const int d = static_cast<int>(diagonal.rows());
  if (first < 0 || first + d > L.n) return false;
  const std::vector<int> position = pivot_positions(L, value, first, d);
  if (position.empty()) return false;
  const auto at = [&](int i, int j) { return position[static_cast<size_t>(i * d + j)]; };
  // The Schur complement from Λ_bb itself, not from the old pivot block plus the change: the
  // old one may hold a short prediction's information, which the change would cancel.
  const Eigen::MatrixXd schur =
      0.5 * (diagonal + diagonal.transpose()) - older_contribution(L, value, first, d);
  Eigen::MatrixXd unit;
  Eigen::VectorXd pivot;
  if (!dense_ldl(schur, &unit, &pivot)) return false;
  for (int j = 0; j < d; ++j) {
    value[at(j, j)] = pivot[j];
    for (int i = j + 1; i < d; ++i) value[at(i, j)] = unit(i, j);
  }
  return true;
}

bool dense_ldl(const Eigen::MatrixXd& a, Eigen::MatrixXd* unit, Eigen::VectorXd* pivot) {
  const auto d = a.rows();
  *unit = Eigen::MatrixXd::Identity(d, d);
  pivot->resize(d);
  Eigen::MatrixXd& u = *unit;
  Eigen::VectorXd& p = *pivot;
  for (Eigen::Index j = 0; j < d; ++j) {
    double dj = a(j, j);
    for (Eigen::Index k = 0; k < j; ++k) dj -= u(j, k) * u(j, k) * p[k];
    if (!(dj > 0.0)) return false;
    p[j] = dj;
    for (Eigen::Index i = j + 1; i < d; ++i) {
      double lij = a(i, j);
      for (Eigen::Index k = 0; k < j; ++k) lij -= u(i, k) * u(j, k) * p[k];
      u(i, j) = lij / dj;
    }
  }
  return true;
}

}  // namespace nav::core::detail
